//! Robot description: one [`RobotConfig`] describes one arm completely.
//!
//! On the host the description is read from a TOML file (`robots/*.toml`, feature `std`); the
//! firmware embeds the same structure serialised with postcard. The field names of the TOML file
//! are the field names of these structures; `docs/robot-file.md` documents them.
//! [`RobotConfig::validate`] turns a description into a [`ValidRobot`], the only form the
//! controller, the chain and the drive manager accept.

mod bounded;
pub mod bus_load;
mod collision;
mod drives;
mod envelope;
mod error;
mod motion;
mod robot;
#[cfg(feature = "std")]
mod toml_file;
mod units;
mod valid;

pub use bus_load::SAMPLE_TIME;
pub use collision::{
    CapsuleConfig, CollisionConfig, DEFAULT_LINK_RADIUS, MAX_CUSTOM_CAPSULES, MAX_EXCLUDED_PAIRS,
};
pub use drives::{DrivesConfig, MAX_PDO_LEAD, PDO_TARGET_LEAD, Streaming, TIME_STAMP_EVERY};
pub use envelope::{Envelope, Frames, MAX_CAPSULES, Placed, frames_at};
pub use error::{ConfigError, ConfigReason};
pub use motion::{MotionConfig, ProfileKind};
pub use robot::{
    BaseConfig, BlendConfig, CartesianLimits, DRIVE_MAX_SPEED, IkConfig, JointConfig, JointDrive,
    JointType, MAX_BOXES, MAX_LINE_SLOWDOWN, MAX_NAME_LEN, MAX_PERIOD_SAMPLES,
    MAX_TRACKING_ITERATIONS, MIN_PERIOD_SAMPLES, RobotConfig, ToolConfig, WorkspaceConfig,
    default_following_error,
};
#[cfg(feature = "std")]
pub use toml_file::{LoadError, load_file, parse_toml};
pub use units::JointUnits;
pub use valid::ValidRobot;
