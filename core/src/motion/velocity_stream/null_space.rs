//! The null-space preference of redundant arms: a pull towards the middle of every joint range.

use crate::kinematics::Joints;
use crate::saturate::saturate;

/// Rate of the pull per unit of distance from mid-range (1/s).
pub const GAIN: f64 = 0.5;

/// The pull is at most this share of each joint's speed limit.
pub const SPEED_SHARE: f64 = 0.25;

/// Joint rates `GAIN · (mid − q)`, each limited to `SPEED_SHARE · max_speed`: the preference
/// `z` that `Chain::joint_rates` projects into the null space.
pub fn mid_range_pull(q: &Joints, mid: &Joints, max_speed: &Joints) -> Joints {
    let mut z = Joints::zeros(q.len());
    for (z, ((q, m), v)) in z
        .iter_mut()
        .zip(q.iter().zip(mid.iter()).zip(max_speed.iter()))
    {
        let cap = SPEED_SHARE * v;
        *z = saturate(GAIN * (m - q), -cap, cap);
    }
    z
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pull_points_to_mid_range_and_is_capped() {
        let q = Joints::from_slice(&[0.0, 1.0, -3.0]).unwrap();
        let mid = Joints::from_slice(&[0.0, 0.0, 0.0]).unwrap();
        let speed = Joints::from_slice(&[1.0, 4.0, 1.0]).unwrap();
        let z = mid_range_pull(&q, &mid, &speed);
        assert_eq!(&z[..], &[0.0, -0.5, 0.25]);
    }
}
