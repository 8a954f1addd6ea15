//! The 1-D trapezoidal velocity profile (spec §4.1, KDL `VelocityProfile_Trap`).

/// A rest-to-rest move from `s0` to `s1`: constant acceleration, cruise, constant deceleration.
///
/// Planned for minimum time under `v_max`/`a_max`, then optionally stretched to a longer
/// duration by uniform time scaling (the shape is kept; velocity scales by `f = D/T`,
/// acceleration by `f²`), so a limit is never exceeded.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Trapezoid {
    s0: f64,
    s1: f64,
    /// End of the acceleration phase.
    t1: f64,
    /// Start of the deceleration phase.
    t2: f64,
    duration: f64,
    /// Signed cruise (peak) velocity.
    velocity: f64,
    /// Signed acceleration of the first phase.
    acceleration: f64,
}

impl Trapezoid {
    /// The minimum-time profile from `s0` to `s1` (`v_max`, `a_max` > 0).
    ///
    /// A zero-length move has duration 0 and stays at `s0` (the seed computed 0/0 here).
    pub fn plan(s0: f64, s1: f64, v_max: f64, a_max: f64) -> Self {
        let distance = libm::fabs(s1 - s0);
        let sign = if s1 < s0 { -1.0 } else { 1.0 };
        let mut p = Self {
            s0,
            s1,
            ..Self::default()
        };
        if distance == 0.0 || !(v_max > 0.0 && a_max > 0.0) {
            return p;
        }
        let t1 = v_max / a_max;
        let ramp = 0.5 * a_max * t1 * t1;
        let cruise_time = (distance - 2.0 * ramp) / v_max;
        if cruise_time > 0.0 {
            p.t1 = t1;
            p.duration = 2.0 * t1 + cruise_time;
            p.t2 = p.duration - t1;
            p.velocity = sign * v_max;
        } else {
            let t1 = crate::math::sqrt(distance / a_max);
            p.t1 = t1;
            p.t2 = t1;
            p.duration = 2.0 * t1;
            p.velocity = sign * a_max * t1;
        }
        p.acceleration = sign * a_max;
        p
    }

    /// The profile stretched to last `duration` if that is longer than its own duration
    /// (spec §4.1 `plan_T`); otherwise unchanged.
    pub fn stretched(self, duration: f64) -> Self {
        if duration.is_nan() || duration <= self.duration || self.duration == 0.0 {
            return self;
        }
        let f = self.duration / duration;
        Self {
            t1: self.t1 / f,
            t2: self.t2 / f,
            duration,
            velocity: self.velocity * f,
            acceleration: self.acceleration * f * f,
            ..self
        }
    }

    /// Duration of the move (s).
    pub fn duration(&self) -> f64 {
        self.duration
    }

    /// Peak speed (absolute).
    pub fn peak_velocity(&self) -> f64 {
        libm::fabs(self.velocity)
    }

    /// Acceleration magnitude.
    pub fn peak_acceleration(&self) -> f64 {
        libm::fabs(self.acceleration)
    }

    /// Position at time `t` after the start; `s0` before, `s1` after the move.
    pub fn position(&self, t: f64) -> f64 {
        if t <= 0.0 {
            self.s0
        } else if t >= self.duration {
            self.s1
        } else if t < self.t1 {
            self.s0 + 0.5 * self.acceleration * t * t
        } else if t < self.t2 {
            self.s0 + 0.5 * self.acceleration * self.t1 * self.t1 + self.velocity * (t - self.t1)
        } else {
            let left = self.duration - t;
            self.s1 - 0.5 * self.acceleration * left * left
        }
    }

    /// Velocity at time `t`.
    pub fn velocity(&self, t: f64) -> f64 {
        if t <= 0.0 || t >= self.duration {
            0.0
        } else if t < self.t1 {
            self.acceleration * t
        } else if t < self.t2 {
            self.velocity
        } else {
            self.acceleration * (self.duration - t)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn full_trapezoid_timing() {
        // 1 m at 0.5 m/s, 1 m/s²: 0.5 s ramps (0.125 m each), 1.5 s cruise.
        let p = Trapezoid::plan(0.0, 1.0, 0.5, 1.0);
        assert!((p.duration() - 2.5).abs() < 1e-12);
        assert!((p.position(0.5) - 0.125).abs() < 1e-12);
        assert!((p.position(1.25) - 0.5).abs() < 1e-12);
        assert!((p.position(2.0) - 0.875).abs() < 1e-12);
        assert_eq!(p.position(2.5), 1.0);
        assert_eq!(p.velocity(1.0), 0.5);
    }

    #[test]
    fn triangle_when_too_short_to_cruise() {
        let p = Trapezoid::plan(2.0, 1.9, 0.5, 1.0);
        // 0.1 m: t1 = √0.1, peak 0.316 m/s < 0.5
        assert!((p.duration() - 2.0 * 0.1f64.sqrt()).abs() < 1e-12);
        assert!((p.position(p.duration() / 2.0) - 1.95).abs() < 1e-12);
        assert!(p.peak_velocity() < 0.5);
    }

    #[test]
    fn stretching_keeps_the_shape_and_ends_on_time() {
        let p = Trapezoid::plan(0.0, 1.0, 0.5, 1.0).stretched(5.0);
        assert_eq!(p.duration(), 5.0);
        assert!((p.peak_velocity() - 0.25).abs() < 1e-12);
        assert!((p.peak_acceleration() - 0.25).abs() < 1e-12);
        assert!((p.position(2.5) - 0.5).abs() < 1e-12);
        // A shorter request never speeds a profile up.
        assert_eq!(
            Trapezoid::plan(0.0, 1.0, 0.5, 1.0)
                .stretched(1.0)
                .duration(),
            2.5
        );
    }

    #[test]
    fn zero_length_move_has_no_duration() {
        let p = Trapezoid::plan(0.3, 0.3, 1.0, 1.0).stretched(2.0);
        assert_eq!(p.duration(), 0.0);
        assert_eq!(p.position(1.0), 0.3);
        assert!(p.position(0.5).is_finite());
    }
}
