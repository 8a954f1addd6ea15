//! Reading robot descriptions from TOML files (host only).

use std::path::Path;

use super::{ConfigError, RobotConfig, ValidRobot};

/// Why a robot file could not be loaded.
#[derive(Debug)]
pub enum LoadError {
    /// The file could not be read.
    Io(std::io::Error),
    /// The text is not valid TOML, or a field is missing, unknown, of the wrong type or too long
    /// (for example more than eight joints); the message names the line and the field.
    Syntax(Box<toml::de::Error>),
    /// The values are well-formed but not acceptable.
    Invalid(ConfigError),
}

impl std::fmt::Display for LoadError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Io(e) => write!(f, "cannot read robot file: {e}"),
            Self::Syntax(e) => write!(f, "robot file: {}", e.to_string().trim_end()),
            Self::Invalid(e) => write!(f, "robot file: {e}"),
        }
    }
}

impl std::error::Error for LoadError {}

/// Parses and validates a robot description from TOML text.
pub fn parse_toml(text: &str) -> Result<ValidRobot, LoadError> {
    let config: RobotConfig = toml::from_str(text).map_err(|e| LoadError::Syntax(Box::new(e)))?;
    config.validate().map_err(LoadError::Invalid)
}

/// Reads, parses and validates a robot file.
pub fn load_file(path: impl AsRef<Path>) -> Result<ValidRobot, LoadError> {
    let text = std::fs::read_to_string(path).map_err(LoadError::Io)?;
    parse_toml(&text)
}
