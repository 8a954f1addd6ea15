//! Limiting a number to a range without a panic path.
//!
//! `f64::clamp` panics when a bound is NaN or `min > max`; a limit computed from inputs (a rate
//! times a time step, a previous value plus a step) cannot always promise neither. These
//! helpers are total: two comparisons, no assertion.

/// `v` limited to `[lo, hi]`: bit for bit `v.clamp(lo, hi)` wherever that does not panic (so
/// a NaN `v` stays NaN: callers that may see one check it first); a NaN bound is ignored and
/// `lo > hi` gives `lo`. Never panics.
pub(crate) fn saturate(v: f64, lo: f64, hi: f64) -> f64 {
    if v < lo {
        lo
    } else if v > hi {
        hi
    } else {
        v
    }
}

/// `delta` limited to `[-step, step]` (a rate limit): a negative or NaN `step` allows no
/// movement at all. Never panics. (The simulations, and the joint limiter's acceleration
/// clamp.)
pub(crate) fn limit_step(delta: f64, step: f64) -> f64 {
    let step = step.max(0.0);
    saturate(delta, -step, step)
}

#[cfg(test)]
mod tests {
    use super::{limit_step, saturate};

    #[test]
    fn saturate_agrees_with_clamp_on_ordered_bounds_and_never_panics() {
        for v in [
            -2.0,
            -1.0,
            0.5,
            1.0,
            3.0,
            1e308,
            -1e308,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ] {
            assert_eq!(saturate(v, -1.0, 1.0), v.clamp(-1.0, 1.0), "{v}");
        }
        assert_eq!(saturate(-0.0, 0.0, 1.0).to_bits(), (-0.0f64).to_bits());
        assert!(saturate(f64::NAN, -1.0, 1.0).is_nan());
        assert_eq!(saturate(0.5, f64::NAN, 1.0), 0.5);
        assert_eq!(saturate(2.0, -1.0, f64::NAN), 2.0);
        assert_eq!(saturate(0.0, 1.0, -1.0), 1.0);
    }

    #[test]
    fn limit_step_allows_nothing_for_a_bad_step() {
        assert_eq!(limit_step(5.0, 2.0), 2.0);
        assert_eq!(limit_step(-5.0, 2.0), -2.0);
        assert_eq!(limit_step(1.5, 2.0), 1.5);
        for step in [-1.0, f64::NAN, 0.0] {
            assert_eq!(limit_step(5.0, step), 0.0, "{step}");
            assert_eq!(limit_step(-5.0, step), 0.0, "{step}");
        }
        assert!(limit_step(f64::NAN, 2.0).is_nan());
        assert_eq!(limit_step(1e308, f64::INFINITY), 1e308);
    }
}
