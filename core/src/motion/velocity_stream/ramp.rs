//! Velocity changes within the joints' acceleration limits.

use crate::kinematics::Joints;

/// The joint velocity one tick after `velocity` on the way to `target`: the largest fraction
/// of the change that keeps every joint's change within `max_change` (acceleration × period).
/// All joints take the same fraction, so the velocity keeps its direction between the old and
/// the new one (the tool's path stays straight while a twist ramps up or down), and a ramp to
/// rest brings every joint to rest on the same tick.
pub fn accelerate(velocity: &Joints, target: &Joints, max_change: &Joints) -> Joints {
    let fraction = velocity
        .iter()
        .zip(target.iter())
        .zip(max_change.iter())
        .map(|((v, t), dv)| {
            let change = libm::fabs(t - v);
            // Written so that a NaN change gives no motion towards it.
            if change <= *dv {
                1.0
            } else if change.is_finite() {
                dv / change
            } else {
                0.0
            }
        })
        .fold(1.0, f64::min)
        .max(0.0);
    let mut out = *velocity;
    for (o, t) in out.iter_mut().zip(target.iter()) {
        let step = fraction * (t - *o);
        if step.is_finite() {
            *o += step;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn joints(v: &[f64]) -> Joints {
        Joints::from_slice(v).unwrap()
    }

    #[test]
    fn the_tightest_joint_sets_the_fraction_for_all() {
        let v = accelerate(
            &joints(&[0.0, 0.0]),
            &joints(&[1.0, 0.5]),
            &joints(&[0.1, 0.1]),
        );
        assert_eq!(&v[..], &[0.1, 0.05]);
        let v = accelerate(
            &joints(&[0.1, 0.05]),
            &joints(&[0.1, 0.1]),
            &joints(&[0.1, 0.1]),
        );
        assert_eq!(&v[..], &[0.1, 0.1]);
        let v = accelerate(
            &joints(&[0.3, -0.2]),
            &joints(&[0.0, 0.0]),
            &joints(&[0.1, 0.1]),
        );
        assert!((v[0] - 0.2).abs() < 1e-15 && (v[1] + 0.2 * 2.0 / 3.0).abs() < 1e-15);
    }

    #[test]
    fn a_nan_target_changes_nothing() {
        let v = accelerate(&joints(&[0.1]), &joints(&[f64::NAN]), &joints(&[0.1]));
        assert_eq!(&v[..], &[0.1]);
    }
}
