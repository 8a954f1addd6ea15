//! The robot description embedded at build time.
//!
//! `build.rs` parses and validates the robot file named by `ROBOT` and serialises it with
//! postcard; here the bytes are decoded and validated again (the decoded values must pass the
//! same checks on the microcontroller as on the host).

use armgate_core::config::{ConfigError, RobotConfig, ValidRobot};

/// The postcard serialisation of the robot description, written by `build.rs`.
static ROBOT_POSTCARD: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/robot.postcard"));

/// Why the embedded description could not be used.
///
/// Only the field is kept for the boot log, not the reason's text: `build.rs` ran the same
/// decoding and validation and fails the build with the full text, so the board can only get
/// here after a core change since the build, and a rebuild prints why. Formatting the texts
/// here would link every reason's message for a log line the board never prints.
pub enum LoadError {
    /// The bytes do not decode as a `RobotConfig` (the core's structures changed incompatibly
    /// since the build script ran; a rebuild fixes it).
    Decode,
    /// The description decoded but is refused.
    Invalid(ConfigError),
}

impl defmt::Format for LoadError {
    fn format(&self, f: defmt::Formatter<'_>) {
        match self {
            Self::Decode => defmt::write!(
                f,
                "embedded robot does not decode: rebuild the firmware (build.rs embeds it anew)"
            ),
            Self::Invalid(e) => defmt::write!(
                f,
                "embedded robot is invalid: field {=str} (joint {}): rebuild the firmware, \
                 build.rs names the reason",
                e.field,
                e.joint
            ),
        }
    }
}

/// Decodes and validates the embedded robot description.
// Once at boot, never on the tick: kept out of `main` and marked cold, which LTO compiles
// smaller (docs/firmware.md, "The boot's share").
#[inline(never)]
#[cold]
pub fn load() -> Result<ValidRobot, LoadError> {
    let config: RobotConfig =
        postcard::from_bytes(ROBOT_POSTCARD).map_err(|_| LoadError::Decode)?;
    config.validate().map_err(LoadError::Invalid)
}

/// Size of the embedded description in bytes (for the boot log).
pub fn embedded_len() -> usize {
    ROBOT_POSTCARD.len()
}
