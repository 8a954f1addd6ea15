//! The simulated drive's motor side: a speed limit, a position-servo lag and a temperature.

use crate::saturate::limit_step;

/// Degrees Celsius above ambient that a joint running at its speed limit settles at.
const HEATING_AT_FULL_SPEED: f64 = 15.0;
/// Thermal time constant (s).
const THERMAL_TIME: f64 = 20.0;

/// The motor and its position loop, in counts.
///
/// The profile's position is first limited in speed (the thesis saw the Whistles top out near
/// 0.9 rad/s, spec §8.2), then followed with a first-order lag, as a stiff position loop
/// does; the temperature creeps up with speed and back to ambient at rest.
#[derive(Clone, Debug, PartialEq)]
pub struct Servo {
    /// Speed limit (counts/s).
    max_speed: f64,
    /// Fraction of the remaining error closed per sample.
    follow: f64,
    /// The speed-limited reference (counts).
    limited: f64,
    /// The motor position (counts).
    position: f64,
    /// The motor speed (counts/s).
    velocity: f64,
    /// Temperature (°C).
    temperature: f64,
    ambient: f64,
}

impl Servo {
    /// A motor at rest at `position`, for samples of `dt` seconds.
    pub fn new(position: f64, max_speed: f64, lag: f64, dt: f64, ambient: f64) -> Self {
        let follow = if lag > 0.0 {
            1.0 - libm::exp(-dt / lag)
        } else {
            1.0
        };
        Self {
            max_speed: libm::fabs(max_speed),
            follow,
            limited: position,
            position,
            velocity: 0.0,
            temperature: ambient,
            ambient,
        }
    }

    /// One sample of `dt` seconds towards `reference` (`None`: motor off, the shaft stays).
    /// A `dt` that is not a positive number is no time at all: nothing changes.
    pub fn sample(&mut self, reference: Option<f64>, dt: f64) {
        if !(dt > 0.0 && dt.is_finite()) {
            return;
        }
        let before = self.position;
        if let Some(reference) = reference {
            let step = self.max_speed * dt;
            self.limited += limit_step(reference - self.limited, step);
            self.position += (self.limited - self.position) * self.follow;
        } else {
            self.limited = self.position;
        }
        self.velocity = if dt > 0.0 {
            (self.position - before) / dt
        } else {
            0.0
        };
        let effort = if self.max_speed > 0.0 {
            libm::fabs(self.velocity) / self.max_speed
        } else {
            0.0
        };
        let settle = self.ambient + HEATING_AT_FULL_SPEED * effort.min(1.0);
        self.temperature += (settle - self.temperature) * (dt / THERMAL_TIME).min(1.0);
    }

    /// The motor position (counts).
    pub fn position(&self) -> f64 {
        self.position
    }

    /// The motor speed (counts/s).
    pub fn velocity(&self) -> f64 {
        self.velocity
    }

    /// The temperature (°C).
    pub fn temperature(&self) -> f64 {
        self.temperature
    }
}
