//! The rest-to-rest double-S profile of one axis.

use super::phases::{self, Ramp};
use super::{JerkLimits, ProfileError};
use crate::saturate::saturate;

/// A jerk-limited move from rest at 0 to rest at a signed distance: seven phases (jerk up,
/// constant acceleration, jerk down, cruise, and the mirror image), position, velocity and
/// acceleration continuous, each within its limit.
///
/// Planned for minimum time, or stretched to a longer duration by lowering the cruise velocity
/// (acceleration and jerk limits kept), which synchronises several axes: plan each with
/// `min_duration = 0`, then [`with_duration`](Self::with_duration) the longest duration. The
/// math, the bounds and the figures: docs/motion.md, "Jerk-limited profiles".
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DoubleS {
    /// Signed distance (the end position).
    distance: f64,
    limits: JerkLimits,
    ramp: Ramp,
    /// Cruise time between the two halves (s).
    cruise_time: f64,
    /// Peak acceleration `j·Tj` (absolute).
    peak_acceleration: f64,
    /// Cruise velocity (absolute).
    peak_velocity: f64,
    duration: f64,
}

impl DoubleS {
    /// The profile from 0 to `distance` within `limits` that lasts the longer of its minimum
    /// time and `min_duration` (the protocol's duration T).
    ///
    /// A zero distance gives a rest of `min_duration`. Errors for a non-finite distance, limits
    /// that are not finite and positive, a negative or non-finite `min_duration`, and times
    /// or speeds that overflow.
    pub fn new(distance: f64, limits: JerkLimits, min_duration: f64) -> Result<Self, ProfileError> {
        if !distance.is_finite() {
            return Err(ProfileError::InvalidDistance);
        }
        let limits = limits.checked()?;
        check_duration(min_duration)?;
        let d = libm::fabs(distance);
        let ramp = if d > 0.0 {
            phases::minimum_time(d, &limits)
        } else {
            Ramp::default()
        };
        Self::from_ramp(distance, limits, ramp)?.with_duration(min_duration)
    }

    /// This move stretched to last `duration` if that is longer; otherwise unchanged. The
    /// cruise velocity drops, acceleration and jerk stay within their limits.
    pub fn with_duration(self, duration: f64) -> Result<Self, ProfileError> {
        check_duration(duration)?;
        if duration <= self.duration {
            return Ok(self);
        }
        let d = libm::fabs(self.distance);
        if d == 0.0 {
            return Ok(Self { duration, ..self });
        }
        let ramp = phases::for_duration(d, &self.limits, &self.ramp, duration);
        Self::from_ramp(self.distance, self.limits, ramp)
    }

    fn from_ramp(distance: f64, limits: JerkLimits, ramp: Ramp) -> Result<Self, ProfileError> {
        let d = libm::fabs(distance);
        let peak_acceleration = limits.jerk * ramp.jerk_time;
        let peak_velocity = peak_acceleration * (ramp.accel_time - ramp.jerk_time);
        let cruise_time = if d > 0.0 {
            (d / peak_velocity - ramp.accel_time).max(0.0)
        } else {
            0.0
        };
        let duration = 2.0 * ramp.accel_time + cruise_time;
        let finite = [peak_acceleration, peak_velocity, cruise_time, duration]
            .iter()
            .all(|x| x.is_finite());
        if !finite || (d > 0.0 && peak_velocity <= 0.0) {
            return Err(ProfileError::OutOfRange);
        }
        Ok(Self {
            distance,
            limits,
            ramp,
            cruise_time,
            peak_acceleration,
            peak_velocity,
            duration,
        })
    }

    /// Duration of the move (s).
    pub fn duration(&self) -> f64 {
        self.duration
    }

    /// The signed distance: the end position.
    pub fn distance(&self) -> f64 {
        self.distance
    }

    /// The limits it was planned with.
    pub fn limits(&self) -> JerkLimits {
        self.limits
    }

    /// Cruise speed (absolute): the largest speed of the move.
    pub fn peak_velocity(&self) -> f64 {
        self.peak_velocity
    }

    /// The largest acceleration magnitude of the move.
    pub fn peak_acceleration(&self) -> f64 {
        self.peak_acceleration
    }

    /// The ends of the seven phases (s); equal ends mark phases of zero length.
    pub fn phase_ends(&self) -> [f64; 7] {
        let Ramp {
            jerk_time: tj,
            accel_time: ta,
            ..
        } = self.ramp;
        let t = self.duration;
        [tj, ta - tj, ta, t - ta, t - ta + tj, t - tj, t]
    }

    /// Position, velocity and acceleration at time `t` after the start: rest at 0 before (and
    /// for a NaN `t`), rest at the distance from [`duration`](Self::duration) on.
    ///
    /// The deceleration half is evaluated as the mirror image of the acceleration half from
    /// the end, so the end state is exact.
    pub fn sample(&self, t: f64) -> (f64, f64, f64) {
        if t.is_nan() || t <= 0.0 {
            return (0.0, 0.0, 0.0);
        }
        if t >= self.duration {
            return (self.distance, 0.0, 0.0);
        }
        let sign = if self.distance < 0.0 { -1.0 } else { 1.0 };
        let (p, v, a) = if t <= 0.5 * self.duration {
            self.first_half(t)
        } else {
            let (p, v, a) = self.first_half(self.duration - t);
            (libm::fabs(self.distance) - p, v, -a)
        };
        (sign * p, sign * v, sign * a)
    }

    /// The unsigned state at `t` in the first half (acceleration, then cruise).
    fn first_half(&self, t: f64) -> (f64, f64, f64) {
        let (tj, ta) = (self.ramp.jerk_time, self.ramp.accel_time);
        let (j, a, vp) = (self.limits.jerk, self.peak_acceleration, self.peak_velocity);
        if t < tj {
            (j * t * t * t / 6.0, 0.5 * j * t * t, j * t)
        } else if t < ta - tj {
            (
                a * (0.5 * t * t - 0.5 * tj * t + tj * tj / 6.0),
                a * (t - 0.5 * tj),
                a,
            )
        } else if t < ta {
            // At most Tj, also when ta − t rounds up: the acceleration stays within its peak.
            let r = saturate(ta - t, 0.0, tj);
            (
                vp * (0.5 * ta - r) + j * r * r * r / 6.0,
                vp - 0.5 * j * r * r,
                j * r,
            )
        } else {
            (vp * (0.5 * ta + (t - ta)), vp, 0.0)
        }
    }
}

fn check_duration(duration: f64) -> Result<(), ProfileError> {
    if duration.is_finite() && duration >= 0.0 {
        Ok(())
    } else {
        Err(ProfileError::InvalidDuration)
    }
}
