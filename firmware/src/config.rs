//! The robot description embedded at build time.
//!
//! `build.rs` parses and validates the robot file named by `ROBOT` and serialises it with
//! postcard; here the bytes are decoded and validated again (the decoded values must pass the
//! same checks on the microcontroller as on the host).

use armgate_core::config::{ConfigError, RobotConfig, ValidRobot};

/// The postcard serialisation of the robot description, written by `build.rs`.
static ROBOT_POSTCARD: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/robot.postcard"));

/// Why the embedded description could not be used.
pub enum LoadError {
    /// The bytes do not decode as a `RobotConfig` (the core's structures changed incompatibly
    /// since the build script ran; a rebuild fixes it).
    Decode(postcard::Error),
    /// The description decoded but is refused.
    Invalid(ConfigError),
}

impl defmt::Format for LoadError {
    fn format(&self, f: defmt::Formatter<'_>) {
        match self {
            Self::Decode(e) => defmt::write!(
                f,
                "embedded robot does not decode: {}",
                defmt::Display2Format(e)
            ),
            Self::Invalid(e) => {
                defmt::write!(f, "embedded robot is invalid: {}", defmt::Display2Format(e))
            }
        }
    }
}

/// Decodes and validates the embedded robot description.
pub fn load() -> Result<ValidRobot, LoadError> {
    let config: RobotConfig = postcard::from_bytes(ROBOT_POSTCARD).map_err(LoadError::Decode)?;
    config.validate().map_err(LoadError::Invalid)
}

/// Size of the embedded description in bytes (for the boot log).
pub fn embedded_len() -> usize {
    ROBOT_POSTCARD.len()
}
