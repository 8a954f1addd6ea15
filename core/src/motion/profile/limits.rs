//! The kinematic limits of one jerk-limited axis.

use super::ProfileError;

/// Velocity, acceleration and jerk bounds (absolute values, in the axis' units per s, s², s³).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JerkLimits {
    /// Largest speed.
    pub velocity: f64,
    /// Largest acceleration magnitude.
    pub acceleration: f64,
    /// Largest jerk magnitude.
    pub jerk: f64,
}

impl JerkLimits {
    /// The three limits, unchecked ([`DoubleS::new`](super::DoubleS::new) checks them).
    pub const fn new(velocity: f64, acceleration: f64, jerk: f64) -> Self {
        Self {
            velocity,
            acceleration,
            jerk,
        }
    }

    /// The limits if all three are finite and positive.
    pub fn checked(self) -> Result<Self, ProfileError> {
        let ok = |x: f64| x.is_finite() && x > 0.0;
        if ok(self.velocity) && ok(self.acceleration) && ok(self.jerk) {
            Ok(self)
        } else {
            Err(ProfileError::InvalidLimits)
        }
    }

    /// These limits for a path parameter `s` that moves an axis by `u · s`: the path may go
    /// `1/|u|` times faster than the axis (limits unchanged for `u = 0`).
    pub fn along(self, u: f64) -> Self {
        let u = libm::fabs(u);
        if u > 0.0 {
            Self::new(self.velocity / u, self.acceleration / u, self.jerk / u)
        } else {
            self
        }
    }

    /// The tighter of two sets of limits, bound by bound.
    pub fn min(self, other: Self) -> Self {
        Self::new(
            self.velocity.min(other.velocity),
            self.acceleration.min(other.acceleration),
            self.jerk.min(other.jerk),
        )
    }
}
