//! Velocity changes within the joints' acceleration (and jerk) limits.

use super::super::joint_stop::StopLimits;
use crate::kinematics::Joints;
use crate::saturate::saturate;

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

/// The joint velocity one tick after `velocity`, reached with `acceleration`, on the way to
/// `target`, within the acceleration and jerk limits (robot files that set `max_jerk`).
///
/// The step is taken along the remaining change `e = target − velocity`, as in
/// [`accelerate`], at a rate `r` of the full acceleration: `r` changes by at most the jerk
/// limits allow per tick, and falls to zero again before the target is reached, so the
/// velocity arrives with no acceleration left (as [`Brake`](super::super::brake::Brake) does
/// for a stop). Each joint's acceleration is then also clamped to its jerk window, which only
/// matters when the target turns (the acceleration the stream had then points elsewhere).
pub fn accelerate_within_jerk(
    velocity: &Joints,
    acceleration: &Joints,
    target: &Joints,
    limits: &StopLimits,
) -> Joints {
    let Some(j_max) = &limits.j_max else {
        return *target;
    };
    let (t, a_max) = (limits.period, &limits.a_max);
    // The way left in seconds at full acceleration (the tightest joint), and the direction
    // whose tightest joint is at its acceleration limit.
    let mut e = *target;
    e.iter_mut().zip(velocity.iter()).for_each(|(e, v)| *e -= v);
    let left = e
        .iter()
        .zip(a_max.iter())
        .map(|(e, a)| libm::fabs(*e) / a)
        .fold(0.0, f64::max);
    if !(left > 0.0 && left.is_finite()) {
        return if left == 0.0 { *target } else { *velocity };
    }
    let u = |i: usize| e.get(i).copied().unwrap_or(0.0) / left;
    // The present rate along it (a least-squares fit, each joint weighed by its limit).
    let (mut along, mut norm) = (0.0, 0.0);
    for (i, (a, limit)) in acceleration.iter().zip(a_max.iter()).enumerate() {
        let w = 1.0 / (limit * limit);
        along += w * a * u(i);
        norm += w * u(i) * u(i);
    }
    let rate = if norm > 0.0 { along / norm } else { 0.0 };
    let rate = if rate.is_finite() {
        rate.clamp(-1.0, 1.0)
    } else {
        0.0
    };
    // The largest change of the rate per tick within every joint's jerk limit.
    let change = a_max
        .iter()
        .zip(j_max.iter())
        .map(|(a, j)| j * t / a)
        .fold(f64::INFINITY, f64::min);
    // What the way still shrinks while a rate `r` ramps down to nothing.
    let ramp_down = |r: f64| t * (r * r / (2.0 * change) - 0.5 * r).max(0.0);
    let (up, hold, down) = ((rate + change).min(1.0), rate.min(1.0), rate - change);
    // Arriving this tick leaves a rate the next tick may drop to nothing.
    let land = left / t;
    let next = if land <= change && down <= land && land <= up {
        land
    } else {
        [up, hold]
            .into_iter()
            .find(|r| left - r * t >= ramp_down(*r))
            .unwrap_or(down)
            .min(land)
    };
    let mut out = *velocity;
    let joints = out.iter_mut().zip(acceleration.iter());
    for (i, ((v, a), (limit, j))) in joints.zip(a_max.iter().zip(j_max.iter())).enumerate() {
        let wanted = next * u(i);
        let eased = saturate(wanted, a - j * t, a + j * t);
        let step = saturate(eased, -limit, *limit) * t;
        if step.is_finite() {
            *v += step;
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

    fn jerk_limits() -> StopLimits {
        StopLimits {
            a_max: joints(&[0.5, 0.05]),
            j_max: Some(joints(&[5.0, 0.1])),
            period: 0.01944,
        }
    }

    /// Ramps from `v` towards `target` and back to rest; every tick within the limits, and
    /// both ends reached with no acceleration left.
    #[test]
    fn the_jerk_limited_ramp_arrives_within_every_limit() {
        let limits = jerk_limits();
        let t = limits.period;
        let (mut v, mut a) = (joints(&[0.0, 0.0]), joints(&[0.0, 0.0]));
        for target in [joints(&[0.4, -0.02]), joints(&[0.0, 0.0])] {
            let mut ticks = 0;
            while (v[0] - target[0]).abs() > 1e-12 || a.iter().any(|a| a.abs() > 1e-9) {
                let next = accelerate_within_jerk(&v, &a, &target, &limits);
                for i in 0..2 {
                    let acc = (next[i] - v[i]) / t;
                    assert!(acc.abs() <= limits.a_max[i] * (1.0 + 1e-9), "a {acc}");
                    let jerk = (acc - a[i]) / t;
                    let j = limits.j_max.unwrap()[i];
                    assert!(jerk.abs() <= j * (1.0 + 1e-9), "jerk {jerk} of {j}");
                    a[i] = acc;
                }
                v = next;
                ticks += 1;
                assert!(ticks < 1000, "never arrives");
            }
            assert!((v[1] - target[1]).abs() < 1e-9);
        }
    }

    #[test]
    fn a_nan_target_changes_nothing() {
        let v = accelerate(&joints(&[0.1]), &joints(&[f64::NAN]), &joints(&[0.1]));
        assert_eq!(&v[..], &[0.1]);
    }
}
