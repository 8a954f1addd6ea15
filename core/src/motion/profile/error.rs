//! Why a jerk-limited profile could not be planned.

use core::fmt;

/// The flat result of planning a [`DoubleS`](super::DoubleS) profile (Ruckig's `Result`, for
/// planning only: sampling cannot fail).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProfileError {
    /// The distance is not a finite number.
    InvalidDistance,
    /// A velocity, acceleration or jerk limit is not a finite positive number.
    InvalidLimits,
    /// The requested duration is negative, infinite or not a number.
    InvalidDuration,
    /// The limits are so small (or the distance or duration so large) that a phase time or
    /// speed does not fit in an `f64`.
    OutOfRange,
}

impl fmt::Display for ProfileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::InvalidDistance => "the distance is not finite",
            Self::InvalidLimits => {
                "a velocity, acceleration or jerk limit is not finite and positive"
            }
            Self::InvalidDuration => "the duration is negative or not finite",
            Self::OutOfRange => "the profile's times or speeds do not fit in an f64",
        })
    }
}

#[cfg(feature = "std")]
impl std::error::Error for ProfileError {}
