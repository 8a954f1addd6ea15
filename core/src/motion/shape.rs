//! Test-path sources usable in place of the Cartesian generator (spec §4.5): a circle and a
//! sinusoid, as the thesis used for its tracking experiments.

use core::f64::consts::TAU;

use super::Refusal;
use crate::math::Vector3;

/// A periodic path relative to the pose where it starts; the orientation is held.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// A circle of `radius` through the start point, centre `radius` away along −`axis_i`,
    /// travelled from `axis_i` towards `axis_j` once per `period`.
    Circle {
        /// Radius (m).
        radius: f64,
        /// Time per revolution (s).
        period: f64,
        /// Axis from the centre to the start point (0 = x, 1 = y, 2 = z).
        axis_i: u8,
        /// Second axis of the circle's plane.
        axis_j: u8,
    },
    /// `amplitude · sin(2π t / period)` along `axis`, centred at the start point.
    Sinusoid {
        /// Amplitude (m): peak-to-peak is twice this.
        amplitude: f64,
        /// Period (s).
        period: f64,
        /// Axis of motion (0 = x, 1 = y, 2 = z).
        axis: u8,
    },
}

impl Shape {
    /// Checks the parameters: positive finite sizes and periods, axes 0..=2, the circle's two
    /// axes distinct (the seed did not check `axis_j`, spec §9 item 41).
    pub fn validate(&self) -> Result<(), Refusal> {
        let ok = match *self {
            Self::Circle {
                radius,
                period,
                axis_i,
                axis_j,
            } => {
                positive(radius) && positive(period) && axis_i < 3 && axis_j < 3 && axis_i != axis_j
            }
            Self::Sinusoid {
                amplitude,
                period,
                axis,
            } => positive(amplitude) && positive(period) && axis < 3,
        };
        if ok {
            Ok(())
        } else {
            Err(Refusal::InvalidNumber)
        }
    }

    /// Offset from the start point at time `t` since the start.
    pub fn offset(&self, t: f64) -> Vector3<f64> {
        match *self {
            Self::Circle {
                radius,
                period,
                axis_i,
                axis_j,
            } => {
                let (s, c) = libm::sincos(TAU * t / period);
                unit(axis_i) * (radius * (c - 1.0)) + unit(axis_j) * (radius * s)
            }
            Self::Sinusoid {
                amplitude,
                period,
                axis,
            } => unit(axis) * (amplitude * libm::sin(TAU * t / period)),
        }
    }

    /// The time at which a shape asked at time `t` to finish comes back to its start point:
    /// the end of the current revolution (circle) or the next zero crossing (sinusoid).
    pub fn end_time(&self, t: f64) -> f64 {
        let step = match *self {
            Self::Circle { period, .. } => period,
            Self::Sinusoid { period, .. } => period / 2.0,
        };
        libm::ceil(t / step) * step
    }
}

fn positive(v: f64) -> bool {
    v.is_finite() && v > 0.0
}

fn unit(axis: u8) -> Vector3<f64> {
    match axis {
        0 => Vector3::x(),
        1 => Vector3::y(),
        _ => Vector3::z(),
    }
}
