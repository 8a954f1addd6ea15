//! Joint positions and drive encoder counts (spec §6.2).

use core::f64::consts::TAU;

use super::robot::{JointConfig, JointType};

/// How one joint's position maps to its drive's encoder counts: `position = counts / scale +
/// home`, where `scale` is counts per radian (`counts_per_rev / 2π`) for a revolute joint and
/// counts per metre for a prismatic one. The sign of `counts_per_rev` sets the direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointUnits {
    scale: f64,
    home: f64,
}

impl JointUnits {
    /// The units of `joint`, or `None` if its drive has no counts per revolution (a joint
    /// without a drive).
    pub fn new(joint: &JointConfig) -> Option<Self> {
        let counts = f64::from(joint.drive.counts_per_rev);
        let scale = match joint.kind {
            JointType::Revolute => counts / TAU,
            JointType::Prismatic => counts,
        };
        (scale != 0.0 && scale.is_finite()).then_some(Self {
            scale,
            home: joint.drive.home,
        })
    }

    /// The joint position (rad or m) at `counts`.
    pub fn position(&self, counts: i32) -> f64 {
        f64::from(counts) / self.scale + self.home
    }

    /// The counts nearest to `position`, rounding halves away from zero; `None` if the position
    /// is not finite or the counts do not fit in 32 bits. (The seed truncated with `floor`, a
    /// bias of half a count, spec §6.2.)
    pub fn counts(&self, position: f64) -> Option<i32> {
        to_i32((position - self.home) * self.scale)
    }

    /// The counts per second nearest to `speed` (rad/s or m/s), rounding halves away from zero.
    /// (The seed's `(int)(x + 0.5)` rounded negative speeds wrongly, spec §9 item 32.)
    pub fn counts_per_second(&self, speed: f64) -> Option<i32> {
        to_i32(speed * self.scale)
    }

    /// The same units with the home moved so that `counts` reads as `position` (spec §6.8).
    pub fn recalibrated(&self, counts: i32, position: f64) -> Self {
        Self {
            home: position - f64::from(counts) / self.scale,
            ..*self
        }
    }
}

/// `value` rounded half away from zero, if it fits in an `i32`.
fn to_i32(value: f64) -> Option<i32> {
    let rounded = libm::round(value);
    let fits = rounded >= f64::from(i32::MIN) && rounded <= f64::from(i32::MAX);
    // In range and finite (NaN fails both comparisons), so the cast is exact.
    fits.then_some(rounded as i32)
}
