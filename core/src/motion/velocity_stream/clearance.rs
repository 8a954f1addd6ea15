//! Slowing down as the arm's body nears an obstacle (issue 35), as Universal Robots' safety
//! planes slow down by the stopping distance: the stream's speed is capped so that a stop
//! begun after the tick would end within the room left, the nearest gap less the margin; at
//! the margin the speed is zero. The stop planned for brakes gently, at [`SLOWING_SHARE`] of
//! the acceleration limits, so the slowing begins well before the arm's own stopping
//! distance (about 2 cm from the column for ranger-mk1 at 0.07 rad/s, where a stop at full
//! deceleration needs 2 mm) and the speed falls smoothly, as the square root of the room.
//!
//! A tick knows the nearest gap at its start (measured by the last tick's check of the body,
//! `Body::clearance_at`) and at the pose where a stop from its velocity would end
//! (`Body::ahead`): their difference is how far that stop closes the gap. At a scale `s` of
//! the velocity the arm moves on for the steady time at `s` times the speed and brakes for
//! `s` times the braking time, so a stop closes `closing · (s·steady + s²·braking) / (steady
//! + braking)` to first order (braking: half the braking time at full speed, the time the
//! braking distance takes at full speed). The next tick's speed is capped at the largest `s`
//! for which this is the room left ([`clearance_scale`], [`speed_cap`]).

/// The share of the acceleration limits the stop a stream slows for brakes with: the
/// slowing begins `1 / SLOWING_SHARE` times as far out as the braking distance needs.
pub const SLOWING_SHARE: f64 = 0.1;

/// The speed share (of the joints' limits) the next tick may ask for: the present `share`
/// scaled so that a gentle stop ([`SLOWING_SHARE`]) ends within `room` (m), when the stop
/// from the present velocity closes the gap by `closing` (m) moving on for `steady` (s) and
/// braking for twice `braking` (s). Infinite when the gap does not close.
pub fn speed_cap(room: f64, closing: f64, (steady, braking): (f64, f64), share: f64) -> f64 {
    let gentle = braking / SLOWING_SHARE;
    // The gap closes at `closing / (steady + braking)` per second at the present speed.
    let total = steady + braking;
    let closing = if total > 0.0 {
        closing * (steady + gentle) / total
    } else {
        closing
    };
    let scale = clearance_scale(room, closing, steady, gentle);
    if scale.is_finite() {
        scale * share
    } else {
        f64::INFINITY
    }
}

/// The largest scale `s ≥ 0` of the velocity whose stop closes the gap by no more than
/// `room` (m), when the stop at `s = 1` closes it by `closing` (m) over `steady` (s) at speed
/// and `braking` (s, half the braking time): `2ρ / (α + √(α² + 4βρ))` for `ρ = room /
/// closing` and the shares `α`, `β` of `steady` and `braking`. Infinite when the gap does
/// not close or nothing is near (infinite room); zero with no room left (and for numbers
/// that are not, NaN).
pub fn clearance_scale(room: f64, closing: f64, steady: f64, braking: f64) -> f64 {
    if closing <= 0.0 || room == f64::INFINITY {
        return f64::INFINITY;
    }
    if room.is_nan() || closing.is_nan() || room <= 0.0 {
        return 0.0;
    }
    let total = steady + braking;
    let (alpha, beta) = if total == 0.0 {
        (1.0, 0.0)
    } else {
        (steady / total, braking / total)
    };
    let rho = room / closing;
    let scale = 2.0 * rho / (alpha + crate::math::sqrt(alpha * alpha + 4.0 * beta * rho));
    if scale.is_nan() { 0.0 } else { scale }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-12
    }

    #[test]
    fn known_scales() {
        // Moving on only: the closing is linear in the speed, half the room half the speed.
        assert!(close(clearance_scale(0.05, 0.1, 0.02, 0.0), 0.5));
        assert!(close(clearance_scale(0.1, 0.1, 0.02, 0.0), 1.0));
        // Braking only: the braking distance grows with the square of the speed, so at a
        // quarter of the room the speed halves (v = √(2ad)).
        assert!(close(clearance_scale(0.025, 0.1, 0.0, 0.3), 0.5));
        assert!(close(clearance_scale(0.1, 0.1, 0.0, 0.3), 1.0));
        // Both, equal shares: s/2 + s²/2 = ρ; ρ = 0.375 gives s = 0.5, ρ = 1 gives 1.
        assert!(close(clearance_scale(0.0375, 0.1, 0.2, 0.2), 0.5));
        assert!(close(clearance_scale(0.1, 0.1, 0.2, 0.2), 1.0));
        // More room than the stop needs: faster is allowed (the caller caps at the target).
        assert!(clearance_scale(0.4, 0.1, 0.2, 0.2) > 1.0);
    }

    #[test]
    fn zero_at_the_margin_infinite_when_not_closing_and_safe_for_non_numbers() {
        assert_eq!(clearance_scale(0.0, 0.1, 0.02, 0.3), 0.0);
        assert_eq!(clearance_scale(-0.01, 0.1, 0.02, 0.3), 0.0);
        assert_eq!(clearance_scale(0.05, 0.0, 0.02, 0.3), f64::INFINITY);
        assert_eq!(clearance_scale(0.05, -0.1, 0.02, 0.3), f64::INFINITY);
        assert_eq!(
            clearance_scale(f64::INFINITY, f64::NAN, 0.02, 0.3),
            f64::INFINITY
        );
        assert_eq!(clearance_scale(f64::NAN, 0.1, 0.02, 0.3), 0.0);
        assert_eq!(clearance_scale(0.05, f64::NAN, 0.02, 0.3), 0.0);
        assert_eq!(clearance_scale(0.05, 0.1, f64::NAN, 0.3), 0.0);
        // No time at all: linear.
        assert!(close(clearance_scale(0.05, 0.1, 0.0, 0.0), 0.5));
    }

    #[test]
    fn the_cap_plans_for_a_gentle_stop() {
        // Braking only: the gentle stop takes ten times as long and closes ten times as far.
        let share = 0.7;
        assert!(close(speed_cap(1.0, 0.1, (0.0, 0.3), share), share));
        assert!(close(speed_cap(0.25, 0.1, (0.0, 0.3), share), 0.5 * share));
        // Moving on only: no braking to derate.
        assert!(close(speed_cap(0.05, 0.1, (0.02, 0.0), share), 0.5 * share));
        assert_eq!(speed_cap(0.05, 0.0, (0.02, 0.3), share), f64::INFINITY);
        assert_eq!(speed_cap(0.0, 0.1, (0.02, 0.3), share), 0.0);
    }

    #[test]
    fn monotonic_in_the_room_and_the_stop_fits() {
        for (steady, braking) in [(0.04, 0.0), (0.04, 0.1), (0.0, 0.5), (0.04, 2.0)] {
            let closing = 0.2;
            let mut last = 0.0;
            for k in 1..=400 {
                let room = k as f64 * 0.001;
                let s = clearance_scale(room, closing, steady, braking);
                assert!(s > last, "{room} {steady} {braking}");
                last = s;
                // The stop at that scale closes exactly the room.
                let closed = closing * (s * steady + s * s * braking) / (steady + braking);
                assert!((closed - room).abs() < 1e-12, "{room}: {closed}");
            }
        }
    }
}
