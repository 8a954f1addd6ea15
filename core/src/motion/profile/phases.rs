//! The closed-form phase times of a rest-to-rest double-S profile.
//!
//! The profile is symmetric: an acceleration half of three phases (jerk `+j` for `Tj`, constant
//! acceleration `j·Tj` for `Ta − 2·Tj`, jerk `−j` for `Tj`, reaching the peak velocity
//! `vp = j·Tj·(Ta − Tj)` after `Ta`), a cruise at `vp`, and the mirrored deceleration half. Its
//! distance is `D = vp·(Ta + Tv)` and its duration `T = 2·Ta + Tv` (Biagiotti & Melchiorri,
//! *Trajectory Planning for Automatic Machines and Robots*, §3.4). So a ramp (`Tj`, `Ta`)
//! determines the rest: the cruise time is `Tv = D/vp − Ta`.

use super::JerkLimits;

/// The bound on the Newton iterations of stretching a profile that stays below its acceleration
/// limit (the cubic case of `phases::for_duration`). It starts within a factor √2 of the
/// root and approaches it monotonically and quadratically: over 2·10⁵ random cases (distances
/// 1e-6..1e5, jerks 1e-2..1e5, durations up to 10³ times the shortest) it stops after at most
/// 9 steps (the unit test `newton_converges_in_a_few_steps` allows 10).
pub const NEWTON_ITERATIONS: usize = 24;

/// The acceleration half of a profile.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Ramp {
    /// Duration of each jerk phase (s).
    pub jerk_time: f64,
    /// Duration of the whole acceleration half (s), at least `2 · jerk_time`.
    pub accel_time: f64,
    /// Whether the peak acceleration is the limit (`jerk_time = a/j`).
    pub at_acceleration_limit: bool,
}

impl Ramp {
    /// A ramp that reaches the acceleration limit and then the peak velocity `vp` (≥ a²/j).
    fn at_limit(vp: f64, l: &JerkLimits) -> Self {
        let jerk_time = l.acceleration / l.jerk;
        Self {
            jerk_time,
            accel_time: jerk_time + vp / l.acceleration,
            at_acceleration_limit: true,
        }
    }

    /// A ramp that only touches its peak acceleration `j·Tj` (no constant-acceleration phase).
    fn below_limit(jerk_time: f64) -> Self {
        Self {
            jerk_time,
            accel_time: 2.0 * jerk_time,
            at_acceleration_limit: false,
        }
    }
}

/// The minimum-time ramp for a distance `d > 0` within limits `l` (finite, positive).
///
/// Three cases: the velocity limit is reached (with or without the acceleration limit,
/// whichever `v·j ≥ a²` says) and the profile cruises; or it is not, and the acceleration
/// limit is (`d ≥ 2a³/j²`: `Ta` solves `a·Ta² − a·Tj·Ta − d = 0`); or neither is
/// (`Tj = ∛(d / 2j)`).
pub(super) fn minimum_time(d: f64, l: &JerkLimits) -> Ramp {
    let (v, a, j) = (l.velocity, l.acceleration, l.jerk);
    let to_velocity = if v * j >= a * a {
        Ramp::at_limit(v, l)
    } else {
        Ramp::below_limit(crate::math::sqrt(v / j))
    };
    if d / v >= to_velocity.accel_time {
        return to_velocity;
    }
    let tj = a / j;
    if d >= 2.0 * a * tj * tj {
        let accel_time = 0.5 * (tj + crate::math::sqrt(tj * tj + 4.0 * d / a));
        Ramp {
            jerk_time: tj,
            accel_time,
            at_acceleration_limit: true,
        }
    } else {
        Ramp::below_limit(libm::cbrt(d / (2.0 * j)))
    }
}

/// The ramp of the profile for distance `d > 0` that lasts `duration`, longer than the
/// profile `from` (the minimum-time one, or one already stretched): same acceleration and
/// jerk limits, a lower cruise velocity `vp`.
///
/// The duration `T(vp) = d/vp + Ta(vp)` falls strictly as `vp` grows wherever the cruise time
/// is not negative, so the solution is unique. With `Ta = vp/a + a/j` (acceleration limit
/// reached, `vp ≥ a²/j`) it is the smaller root of `vp²/a − (T − a/j)·vp + d = 0`. Below that
/// (`Ta = 2·Tj`, `vp = j·Tj²`) `g(Tj) = d/(j·Tj²) + 2·Tj − T` is convex and falling there:
/// Newton's method from `√(d/(j·T))` (where `g > 0`, within a factor √2 of the root) climbs
/// monotonically to the root; it stops when it no longer moves, after at most
/// [`NEWTON_ITERATIONS`].
pub(super) fn for_duration(d: f64, l: &JerkLimits, from: &Ramp, duration: f64) -> Ramp {
    let (a, j) = (l.acceleration, l.jerk);
    let tj = a / j;
    // The duration at the boundary vp = a²/j between the two cases.
    let boundary = d / (a * tj) + 2.0 * tj;
    if from.at_acceleration_limit && duration <= boundary {
        let b = duration - tj;
        let root = crate::math::sqrt((b * b - 4.0 * d / a).max(0.0));
        // 2d / (b + root) is the smaller root without cancellation.
        return Ramp::at_limit(2.0 * d / (b + root), l);
    }
    Ramp::below_limit(jerk_time_for(d, j, duration).0)
}

/// The jerk time `Tj` of a profile below the acceleration limit that lasts `duration`, and the
/// Newton steps taken: the root of `g(Tj) = d/(j·Tj²) + 2·Tj − duration` (see
/// [`for_duration`]).
fn jerk_time_for(d: f64, j: f64, duration: f64) -> (f64, usize) {
    let mut s = crate::math::sqrt(d / (j * duration));
    for step in 0..NEWTON_ITERATIONS {
        let g = d / (j * s * s) + 2.0 * s - duration;
        let slope = 2.0 - 2.0 * d / (j * s * s * s);
        if !(g > 0.0 && slope < 0.0) {
            return (s, step);
        }
        let next = s - g / slope;
        if next.is_nan() || next <= s {
            return (s, step);
        }
        s = next;
    }
    (s, NEWTON_ITERATIONS)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    /// The Newton iteration stops well within its bound wherever the cubic case applies: from
    /// just above the shortest duration to a thousand times longer, over eleven decades of
    /// distance and seven of jerk.
    #[test]
    fn newton_converges_in_a_few_steps() {
        let mut rng = SplitMix64::new(7);
        let mut most = 0;
        for _ in 0..200_000 {
            let d = rng.log_uniform(1e-6, 1e5);
            let j = rng.log_uniform(1e-2, 1e5);
            // The shortest duration of a profile that never cruises nor reaches its
            // acceleration limit: Tj = ∛(d / 2j), T = 4·Tj.
            let shortest = 4.0 * libm::cbrt(d / (2.0 * j));
            let duration = shortest * (1.0 + rng.log_uniform(1e-12, 1e3));
            let (tj, steps) = jerk_time_for(d, j, duration);
            most = most.max(steps);
            let residual = d / (j * tj * tj) + 2.0 * tj - duration;
            assert!(
                residual.abs() <= 1e-12 * duration,
                "{d} {j} {duration}: {residual}"
            );
        }
        assert!(most <= 10, "{most} steps");
    }
}
