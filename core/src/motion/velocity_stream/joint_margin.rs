//! Joint limits approached with a margin and a slow-down instead of a hard clamp.

/// The margin kept from each joint limit, as a share of the joint's range.
pub const MARGIN_SHARE: f64 = 0.02;

/// The speed at which a joint at `q` moving in the direction of `rate` can still stop, at
/// acceleration `acceleration`, before the margin bound (`lower` or `upper`, the limits minus
/// the margin) and one period `period` of travel: `√(2·a·d)` for the distance `d` left.
/// Moving away from both bounds is not limited (infinity).
pub fn braking_speed(
    q: f64,
    rate: f64,
    (lower, upper): (f64, f64),
    acceleration: f64,
    period: f64,
) -> f64 {
    let left = if rate > 0.0 {
        upper - q
    } else if rate < 0.0 {
        q - lower
    } else {
        return f64::INFINITY;
    };
    // The step of this tick is taken before the braking starts.
    let distance = left - libm::fabs(rate) * period;
    if distance > 0.0 {
        crate::math::sqrt(2.0 * acceleration * distance)
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn speed_falls_with_the_square_root_of_the_distance_left() {
        let bounds = (-1.0, 1.0);
        assert_eq!(braking_speed(0.0, 0.0, bounds, 2.0, 0.01), f64::INFINITY);
        // 0.5 left, minus 0.1 × 0.01 of this tick's step.
        let v = braking_speed(0.5, 0.1, bounds, 2.0, 0.01);
        assert!((v - crate::math::sqrt(4.0 * 0.499)).abs() < 1e-12);
        let v = braking_speed(-0.5, -0.1, bounds, 2.0, 0.01);
        assert!((v - crate::math::sqrt(4.0 * 0.499)).abs() < 1e-12);
        assert_eq!(braking_speed(1.0, 0.1, bounds, 2.0, 0.01), 0.0);
        assert_eq!(braking_speed(1.5, 0.1, bounds, 2.0, 0.01), 0.0);
        // Away from the bound it is near: no limit.
        assert!(braking_speed(1.0, -0.1, bounds, 2.0, 0.01) > 1.0);
    }
}
