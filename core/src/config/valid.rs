//! [`ValidRobot`]: a robot description that passed validation, and nothing else.

use core::ops::Deref;

use super::{ConfigError, JointType, RobotConfig};

/// A robot description that passed [`RobotConfig::validate`]: the only input of the
/// controller, the kinematic chain and the drive manager, so none of them can be handed a
/// description that was never checked.
///
/// Only [`RobotConfig::validate`] makes one (the field is private); it reads like the
/// description through `Deref`. To change a value, take the description back with
/// [`into_config`](Self::into_config), change it and validate again.
///
/// ```compile_fail
/// # fn skip(config: armgate_core::config::RobotConfig) {
/// // The field is private: the only way in is `RobotConfig::validate`.
/// let robot = armgate_core::config::ValidRobot { config };
/// # }
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct ValidRobot {
    config: RobotConfig,
}

impl ValidRobot {
    /// Wraps a description that `check` accepted; the one constructor.
    pub(super) fn checked(config: RobotConfig) -> Self {
        Self { config }
    }

    /// The validated description.
    pub fn config(&self) -> &RobotConfig {
        &self.config
    }

    /// The description, to change and validate again.
    pub fn into_config(self) -> RobotConfig {
        self.config
    }

    /// Suspicious values that validation lets pass: a revolute joint whose limits reach beyond
    /// ±2π (more than a turn each way: written in degrees?), as (joint from 0, min, max). The
    /// shells print them at load.
    pub fn wide_limits(&self) -> impl Iterator<Item = (usize, f64, f64)> + '_ {
        let turn = core::f64::consts::TAU;
        self.config
            .joints
            .iter()
            .enumerate()
            .filter(move |(_, j)| j.kind == JointType::Revolute && (j.min < -turn || j.max > turn))
            .map(|(k, j)| (k, j.min, j.max))
    }

    /// This description with `change` applied, validated again.
    pub fn edit(self, change: impl FnOnce(&mut RobotConfig)) -> Result<Self, ConfigError> {
        let mut config = self.config;
        change(&mut config);
        config.validate()
    }
}

impl Deref for ValidRobot {
    type Target = RobotConfig;

    fn deref(&self) -> &RobotConfig {
        &self.config
    }
}

impl TryFrom<RobotConfig> for ValidRobot {
    type Error = ConfigError;

    fn try_from(config: RobotConfig) -> Result<Self, ConfigError> {
        config.validate()
    }
}
