//! The robot description structures and their validation.

use heapless::{String, Vec};
use serde::{Deserialize, Serialize};

use super::bus_load::whole_samples;
use super::collision::{CollisionConfig, check_link_radius};
use super::drives::DrivesConfig;
use super::envelope::{Envelope, Placed, frames_at, tilt};
use super::error::{ConfigError, ConfigReason};
use super::motion::{MotionConfig, ProfileKind};
use super::units::JointUnits;
use super::valid::ValidRobot;
use crate::MAX_JOINTS;
use crate::geometry::Capsule;
use crate::math::{Frame, Joints, Rotation3, Vector3};

/// Longest robot name, in bytes.
pub const MAX_NAME_LEN: usize = 32;
/// Most workspace exclusion boxes a description may hold.
pub const MAX_BOXES: usize = 16;
/// The shortest control period, in 360 µs drive samples (1.08 ms): below 1 ms a tick cannot
/// finish in time and the shells would spin.
pub const MIN_PERIOD_SAMPLES: u16 = 3;
/// The longest control period, in 360 µs drive samples (0.99972 s): the longest under 1 s.
pub const MAX_PERIOD_SAMPLES: u16 = 2777;

/// A complete robot description: geometry, limits, drives, workspace and control period.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotConfig {
    /// Short name of the arm, e.g. `ranger-mk1`.
    pub name: String<MAX_NAME_LEN>,
    /// Kinematic control period in seconds (the seed: 0.01944 s = 54 × 360 µs): a whole number
    /// of 360 µs drive samples, [`MIN_PERIOD_SAMPLES`] to [`MAX_PERIOD_SAMPLES`].
    pub control_period: f64,
    /// The joints from the base outwards (1..=8).
    #[serde(deserialize_with = "super::bounded::deserialize")]
    pub joints: Vec<JointConfig, MAX_JOINTS>,
    /// The fixed transform from the last link frame to the tool frame.
    #[serde(default)]
    pub tool: ToolConfig,
    /// Where the base frame {0} lies in the world (measurement) frame; absent = identity.
    #[serde(default)]
    pub base: BaseConfig,
    /// Bus-wide drive settings.
    pub drives: DrivesConfig,
    /// Cartesian generator limits (the seed's `trajgen.cpf`).
    pub cartesian: CartesianLimits,
    /// Workspace bounds and exclusion boxes (the seed's `wslimits.cpf`).
    pub workspace: WorkspaceConfig,
    /// Inverse-kinematics tuning; defaults suit every shipped arm.
    #[serde(default)]
    pub ik: IkConfig,
    /// Default blend tolerances of via points; absent = 0, stop at every via point (the seed).
    #[serde(default)]
    pub blend: BlendConfig,
    /// The generators' velocity profile; absent = the seed's trapezoids.
    #[serde(default)]
    pub motion: MotionConfig,
    /// The arm's body as capsules and what they are checked against; absent = the default
    /// body from the DH parameters.
    #[serde(default)]
    pub collision: CollisionConfig,
}

/// Whether a joint turns (revolute) or slides (prismatic).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum JointType {
    /// The joint variable is the angle θ_i (rad).
    Revolute,
    /// The joint variable is the offset d_i (m).
    Prismatic,
}

/// One joint: Craig's *modified* DH parameters, limits and its drive.
///
/// The link transform is `RotX(alpha) · TransX(a) · RotZ(θ) · TransZ(d)` with, for a revolute
/// joint, `θ = q + theta` and `d` constant, and for a prismatic joint `d = q + d` and `θ = theta`.
/// So `theta` (revolute) or `d` (prismatic) is a constant offset added to the joint variable.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointConfig {
    /// Revolute or prismatic.
    #[serde(rename = "type")]
    pub kind: JointType,
    /// α_{i-1}: twist about the previous x axis (rad).
    pub alpha: f64,
    /// a_{i-1}: length along the previous x axis (m).
    pub a: f64,
    /// d_i: offset along this z axis (m); added to q for a prismatic joint.
    pub d: f64,
    /// θ_i: angle about this z axis (rad); added to q for a revolute joint.
    pub theta: f64,
    /// β_{i-1}: Hayati's extra rotation about the y axis after `TransX(a)` (rad, default 0).
    /// Only kinematic calibration sets it: it models a small misalignment of nearly parallel
    /// consecutive axes, where the DH `d` would jump (`docs/calibration.md`).
    #[serde(default)]
    pub beta: f64,
    /// Lower joint limit (rad or m).
    pub min: f64,
    /// Upper joint limit (rad or m).
    pub max: f64,
    /// Joint generator velocity limit (rad/s or m/s; the seed's `naxestrajgen.cpf`).
    pub max_velocity: f64,
    /// Joint generator acceleration limit (rad/s² or m/s²).
    pub max_acceleration: f64,
    /// Joint limiter rate limit on set-points (rad/s or m/s; the seed's `MaxRates`).
    pub max_rate: f64,
    /// Joint generator jerk limit (rad/s³ or m/s³); required by the jerk-limited profile.
    #[serde(default)]
    pub max_jerk: Option<f64>,
    /// The most the measured position may differ from the command (rad or m) before the
    /// controller stops the arm (`ER43`, stop cause 9); none: [`default_following_error`].
    #[serde(default)]
    pub max_following_error: Option<f64>,
    /// The servo drive of this joint.
    pub drive: JointDrive,
    /// The radius of this joint's link (the body it moves) in the collision model (m, ≥ 0);
    /// absent = [`DEFAULT_LINK_RADIUS`](super::collision::DEFAULT_LINK_RADIUS).
    #[serde(default)]
    pub link_radius: Option<f64>,
}

/// The drive of one joint.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointDrive {
    /// CANopen node id, 1..=127; 0 means no drive (the measurement mirrors the command).
    pub node_id: u8,
    /// Encoder counts per joint revolution (per metre for a prismatic joint); the sign sets the
    /// direction.
    pub counts_per_rev: i32,
    /// Joint position at zero encoder counts (rad or m).
    pub home: f64,
    /// The speed the drive is configured to move at most (rad/s or m/s): a joint whose
    /// `max_rate` is higher is refused at load, since the drive would fall behind its
    /// commands. None: [`DRIVE_MAX_SPEED`], the seed's Whistles (the simulated Whistle follows
    /// this value).
    #[serde(default = "default_drive_speed")]
    pub max_speed: f64,
    /// The acceleration the drive is configured for at most (rad/s² or m/s²), if it limits
    /// one: a joint whose `max_acceleration` is higher is refused at load.
    #[serde(default)]
    pub max_acceleration: Option<f64>,
}

/// The speed limit of a drive the robot file says nothing about (rad/s or m/s): the thesis
/// observed the seed's Whistles to move at about 0.9 rad/s.
pub const DRIVE_MAX_SPEED: f64 = 0.9;

fn default_drive_speed() -> f64 {
    DRIVE_MAX_SPEED
}

/// Control periods of command a joint may lag behind at its `max_rate` by default (the drives
/// execute a set-point two or three periods after it is sent, and report it a period later).
const FOLLOWING_PERIODS: f64 = 10.0;
/// The following error always allowed by default (rad or m): the servo's own settling.
const FOLLOWING_FLOOR: f64 = 0.01;

/// The default `max_following_error` of a joint (rad or m): what it travels in
/// [`FOLLOWING_PERIODS`] control periods at its `max_rate`, plus [`FOLLOWING_FLOOR`]
/// (ranger-mk1: 0.049 rad; ur5: 0.168 rad).
pub fn default_following_error(max_rate: f64, control_period: f64) -> f64 {
    FOLLOWING_PERIODS * max_rate * control_period + FOLLOWING_FLOOR
}

/// The tool frame relative to the last link frame:
/// `DH(a, alpha, d, theta) · Trans(xyz) · RPY(rpy)`.
///
/// The four DH values are the seed's `EndEffDH`; `xyz`/`rpy` give a general transform. Every
/// field defaults to zero, so an absent `[tool]` is the identity.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ToolConfig {
    /// a_n (m).
    pub a: f64,
    /// α_n (rad).
    pub alpha: f64,
    /// d_T (m).
    pub d: f64,
    /// θ_T (rad).
    pub theta: f64,
    /// Extra translation after the DH part (m).
    pub xyz: [f64; 3],
    /// Extra rotation after the translation: roll, pitch, yaw (rad), `Rz·Ry·Rx`.
    pub rpy: [f64; 3],
}

/// The base frame {0} in the world frame: `Trans(xyz) · RPY(rpy)`. Every field defaults to zero,
/// so an absent `[base]` puts the base at the world origin. Kinematic calibration fits it to the
/// frame of the measuring instrument.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BaseConfig {
    /// Origin of {0} in the world frame (m).
    pub xyz: [f64; 3],
    /// Orientation of {0}: roll, pitch, yaw (rad), `Rz·Ry·Rx`.
    pub rpy: [f64; 3],
}

/// Per-axis Cartesian generator limits for (x, y, z, rx, ry, rz).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CartesianLimits {
    /// m/s for x, y, z; rad/s for rx, ry, rz.
    pub max_velocity: [f64; 6],
    /// m/s² for x, y, z; rad/s² for rx, ry, rz.
    pub max_acceleration: [f64; 6],
    /// m/s³ for x, y, z; rad/s³ for rx, ry, rz; required by the jerk-limited profile.
    #[serde(default)]
    pub max_jerk: Option<[f64; 6]>,
}

/// Allowed region of the tool position, in the base frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WorkspaceConfig {
    /// `[x_min, x_max, y_min, y_max, z_min, z_max]` (m).
    pub bounds: [f64; 6],
    /// Axis-aligned exclusion boxes, each `[x_min, x_max, y_min, y_max, z_min, z_max]` (m).
    #[serde(default, deserialize_with = "super::bounded::deserialize")]
    pub boxes: Vec<[f64; 6], MAX_BOXES>,
}

/// How closely a via-point sequence passes its intermediate via points (docs/motion.md,
/// "Blended via points"): within this distance of a via point the sequence blends into the
/// next leg without stopping. 0 stops at every via point and checks that it was reached, as
/// the seed did. A slot's own tolerance (`VT`, `jT`) overrides the default.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BlendConfig {
    /// Cartesian via points: m + rad (the via-point distance, spec §4.4), ≥ 0.
    pub cartesian: f64,
    /// Joint via points: Euclidean over the joints, rad (m for prismatic joints), ≥ 0.
    pub joint: f64,
}

/// The most iterations one tracking solve may take (`ik.tracking_iterations`): a tick runs a
/// few solves, and 65,535 each would not end within any control period.
pub const MAX_TRACKING_ITERATIONS: u16 = 100;

/// The most `ik.line_slowdown` may be: beyond it a line is hardly moving where it is slowed.
pub const MAX_LINE_SLOWDOWN: f64 = 1000.0;

/// Inverse-kinematics tuning.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct IkConfig {
    /// Convergence tolerance on position (m) and on orientation (rad).
    pub tolerance: f64,
    /// Iteration limit of one tracking solve, 1..=[`MAX_TRACKING_ITERATIONS`].
    pub tracking_iterations: u16,
    /// Total iteration budget of one global solve, over all restarts.
    pub global_iterations: u16,
    /// Check the straight line of every Cartesian move (BG, each VE leg) before starting it,
    /// and refuse a move the arm cannot follow (`ER25`/`ER26` with where along the line).
    /// False: the seed's behaviour, the arm moves until the IK fails, then holds (`WN22`).
    pub check_lines: bool,
    /// How many times its `max_rate` a joint may need at a line's cruise speed (averaged over
    /// a step of the check) before the check refuses the line (`ER25 … jN too fast`); up to
    /// it the tick follows the line slower, within the acceleration limits. 1 refuses every
    /// line that would need slowing down. 1 to [`MAX_LINE_SLOWDOWN`].
    pub line_slowdown: f64,
}

impl Default for IkConfig {
    fn default() -> Self {
        Self {
            tolerance: 1e-9,
            tracking_iterations: 20,
            global_iterations: 2000,
            check_lines: true,
            line_slowdown: 100.0,
        }
    }
}

impl RobotConfig {
    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// Each joint's `max_following_error`, or its [`default_following_error`].
    pub fn following_limits(&self) -> Joints {
        self.per_joint(|joint| {
            joint
                .max_following_error
                .unwrap_or_else(|| default_following_error(joint.max_rate, self.control_period))
        })
    }

    /// Every joint at its drive's home position (zero encoder counts).
    pub fn home(&self) -> Joints {
        self.per_joint(|joint| joint.drive.home)
    }

    /// One value per joint, e.g. `config.per_joint(|j| j.max_velocity)`.
    pub fn per_joint(&self, value: impl Fn(&JointConfig) -> f64) -> Joints {
        self.per_joint_of(&value)
    }

    /// [`per_joint`](Self::per_joint)'s loop, compiled once for every caller's `value`.
    #[inline(never)]
    fn per_joint_of(&self, value: &dyn Fn(&JointConfig) -> f64) -> Joints {
        let mut q = Joints::zeros(self.dof());
        for (q, joint) in q.iter_mut().zip(&self.joints) {
            *q = value(joint);
        }
        q
    }

    /// Checks every value, so that nothing downstream has to, and returns the description as
    /// the one type the controller, the chain and the drive manager accept: finite numbers,
    /// positive limits, `min ≤ home ≤ max`, a control period of whole drive samples in range,
    /// valid node ids, bit rate and unit mode, a bus load under `drives.max_bus_load`,
    /// well-formed boxes.
    pub fn validate(self) -> Result<ValidRobot, ConfigError> {
        self.check()?;
        Ok(ValidRobot::checked(self))
    }

    fn check(&self) -> Result<(), ConfigError> {
        let top = |field, reason| ConfigError::top(field, reason);
        if self.name.is_empty() {
            return Err(top("name", ConfigReason::Empty));
        }
        let samples = whole_samples(self.control_period)
            .filter(|n| (MIN_PERIOD_SAMPLES..=MAX_PERIOD_SAMPLES).contains(n));
        if samples.is_none() {
            return Err(top("control_period", ConfigReason::ControlPeriod));
        }
        if self.joints.is_empty() {
            return Err(top("joints", ConfigReason::NoJoints));
        }
        for (index, joint) in self.joints.iter().enumerate() {
            joint
                .validate()
                .map_err(|(field, reason)| ConfigError::joint(index, field, reason))?;
            let node = joint.drive.node_id;
            let duplicate = node != 0
                && self
                    .joints
                    .iter()
                    .take(index)
                    .any(|other| other.drive.node_id == node);
            if duplicate {
                return Err(ConfigError::joint(
                    index,
                    "drive.node_id",
                    ConfigReason::DuplicateNodeId,
                ));
            }
        }
        self.tool.validate().map_err(|(f, r)| top(f, r))?;
        let base = self.base.xyz.iter().chain(&self.base.rpy);
        if base.clone().any(|v| !v.is_finite()) {
            return Err(top("base", ConfigReason::NotFinite));
        }
        self.drives.validate().map_err(|(f, r)| top(f, r))?;
        super::bus_load::check(self)?;
        for (v, a) in self
            .cartesian
            .max_velocity
            .iter()
            .zip(&self.cartesian.max_acceleration)
        {
            positive(*v).map_err(|r| top("cartesian.max_velocity", r))?;
            positive(*a).map_err(|r| top("cartesian.max_acceleration", r))?;
        }
        self.check_jerk_limits()?;
        check_box(&self.workspace.bounds).map_err(|r| top("workspace.bounds", r))?;
        for b in &self.workspace.boxes {
            check_box(b).map_err(|r| top("workspace.boxes", r))?;
            // An exclusion box of zero thickness excludes nothing a straight piece of a way
            // could not slip through between two points (issue 33): refused.
            let flat = b
                .chunks_exact(2)
                .any(|pair| matches!(pair, [lo, hi] if lo >= hi));
            if flat {
                return Err(top("workspace.boxes", ConfigReason::NoVolume));
            }
        }
        self.ik.validate().map_err(|(f, r)| top(f, r))?;
        not_negative(self.blend.cartesian).map_err(|r| top("blend.cartesian", r))?;
        not_negative(self.blend.joint).map_err(|r| top("blend.joint", r))?;
        self.collision
            .validate(self.dof() + 1)
            .map_err(|(f, r)| top(f, r))?;
        self.check_home_clear()
    }

    /// The arm must not start in collision: at home, no capsule of the body within the margin
    /// of a box, the bounds or another capsule it is checked against.
    fn check_home_clear(&self) -> Result<(), ConfigError> {
        let envelope = Envelope::new(self);
        let mut placed: Placed = [Capsule::default(); super::envelope::MAX_CAPSULES];
        envelope.place(&frames_at(self, &self.home()), &mut placed);
        match envelope.first_hit(&placed) {
            Some(hit) => Err(ConfigError::top(
                "collision",
                ConfigReason::HomeInCollision(hit),
            )),
            None => Ok(()),
        }
    }

    /// `Trans(xyz) · RPY(rpy)`: the base frame {0} in the world.
    pub fn base_frame(&self) -> Frame {
        let [roll, pitch, yaw] = self.base.rpy;
        Frame::from_parts(
            Vector3::from(self.base.xyz).into(),
            Rotation3::from_euler_angles(roll, pitch, yaw),
        )
    }

    /// Jerk limits, where given, are finite and positive; the jerk-limited profile needs them
    /// for every joint and Cartesian component.
    fn check_jerk_limits(&self) -> Result<(), ConfigError> {
        let required = self.motion.profile == ProfileKind::JerkLimited;
        let check = |limit: Option<f64>| match limit {
            Some(j) => positive(j),
            None if required => Err(ConfigReason::MissingJerkLimit),
            None => Ok(()),
        };
        for (index, joint) in self.joints.iter().enumerate() {
            check(joint.max_jerk).map_err(|r| ConfigError::joint(index, "max_jerk", r))?;
        }
        match self.cartesian.max_jerk {
            Some(limits) => limits.iter().try_for_each(|j| positive(*j)),
            None => check(None),
        }
        .map_err(|r| ConfigError::top("cartesian.max_jerk", r))
    }

    /// Per-joint jerk limits if the robot file chose the jerk-limited profile (validation made
    /// sure every joint has one).
    pub fn joint_jerk_limits(&self) -> Option<Joints> {
        (self.motion.profile == ProfileKind::JerkLimited)
            .then(|| self.per_joint(|j| j.max_jerk.unwrap_or(f64::INFINITY)))
    }

    /// Cartesian jerk limits (x, y, z, rx, ry, rz) if the robot file chose the jerk-limited
    /// profile.
    pub fn cartesian_jerk_limits(&self) -> Option<[f64; 6]> {
        if self.motion.profile == ProfileKind::JerkLimited {
            self.cartesian.max_jerk
        } else {
            None
        }
    }
}

impl JointConfig {
    /// The transform from the previous joint frame to this one at joint value `q`:
    /// `RotX(alpha) · TransX(a) · RotY(beta) · RotZ(θ) · TransZ(d)`.
    pub fn frame(&self, q: f64) -> Frame {
        let (theta, d) = match self.kind {
            JointType::Revolute => (self.theta + q, self.d),
            JointType::Prismatic => (self.theta, self.d + q),
        };
        crate::math::dh(self.a, self.alpha, 0.0, 0.0)
            * tilt(self.beta)
            * crate::math::dh(0.0, 0.0, d, theta)
    }

    fn validate(&self) -> Result<(), (&'static str, ConfigReason)> {
        let geometry = [
            ("alpha", self.alpha),
            ("a", self.a),
            ("d", self.d),
            ("theta", self.theta),
            ("beta", self.beta),
        ];
        for (field, value) in geometry {
            finite(value).map_err(|r| (field, r))?;
        }
        finite(self.min).map_err(|r| ("min", r))?;
        finite(self.max).map_err(|r| ("max", r))?;
        if self.min > self.max {
            return Err(("min", ConfigReason::MinAboveMax));
        }
        positive(self.max_velocity).map_err(|r| ("max_velocity", r))?;
        positive(self.max_acceleration).map_err(|r| ("max_acceleration", r))?;
        positive(self.max_rate).map_err(|r| ("max_rate", r))?;
        if let Some(limit) = self.max_following_error {
            positive(limit).map_err(|r| ("max_following_error", r))?;
        }
        self.within_drive()?;
        finite(self.drive.home).map_err(|r| ("drive.home", r))?;
        check_link_radius(self.link_radius).map_err(|r| ("link_radius", r))?;
        if !(self.min..=self.max).contains(&self.drive.home) {
            return Err(("drive.home", ConfigReason::HomeOutsideLimits));
        }
        if self.drive.node_id > 127 {
            return Err(("drive.node_id", ConfigReason::NodeIdOutOfRange));
        }
        if self.drive.node_id != 0 && self.drive.counts_per_rev == 0 {
            return Err(("drive.counts_per_rev", ConfigReason::ZeroCounts));
        }
        // Every position within the limits must be a set-point the drive can take.
        if self.drive.node_id != 0 {
            let units =
                JointUnits::new(self).ok_or(("drive.counts_per_rev", ConfigReason::ZeroCounts))?;
            if units.counts(self.min).is_none() || units.counts(self.max).is_none() {
                return Err(("drive.counts_per_rev", ConfigReason::CountsOverflow));
            }
        }
        Ok(())
    }
}

impl JointConfig {
    /// Refuses a joint whose rate or acceleration limit exceeds what its drive is configured
    /// for, naming both: the drive would fall behind the commands (issue 33: ur5's joints at
    /// 3.14 rad/s on drives limited to 0.9 lagged 4.4 rad). A joint without a drive (node 0)
    /// has nothing to exceed.
    fn within_drive(&self) -> Result<(), (&'static str, ConfigReason)> {
        if self.drive.node_id == 0 {
            return Ok(());
        }
        positive(self.drive.max_speed).map_err(|r| ("drive.max_speed", r))?;
        let exceeds = |value: f64, drive: f64, drive_field| ConfigReason::ExceedsDrive {
            value_milli: milli(value),
            drive_milli: milli(drive),
            drive_field,
        };
        if self.max_rate > self.drive.max_speed {
            let why = exceeds(self.max_rate, self.drive.max_speed, "drive.max_speed");
            return Err(("max_rate", why));
        }
        if let Some(drive) = self.drive.max_acceleration {
            positive(drive).map_err(|r| ("drive.max_acceleration", r))?;
            if self.max_acceleration > drive {
                let why = exceeds(self.max_acceleration, drive, "drive.max_acceleration");
                return Err(("max_acceleration", why));
            }
        }
        Ok(())
    }
}

/// A positive value in thousandths, rounded up (so that a value above its limit never prints
/// equal to it); saturating.
fn milli(v: f64) -> u32 {
    libm::ceil(v * 1000.0) as u32
}

impl ToolConfig {
    /// `DH(a, alpha, d, theta) · Trans(xyz) · RPY(rpy)`: the tool frame in the last joint
    /// frame.
    pub fn frame(&self) -> Frame {
        let [roll, pitch, yaw] = self.rpy;
        crate::math::dh(self.a, self.alpha, self.d, self.theta)
            * Frame::from_parts(
                Vector3::from(self.xyz).into(),
                Rotation3::from_euler_angles(roll, pitch, yaw),
            )
    }

    fn validate(&self) -> Result<(), (&'static str, ConfigReason)> {
        let dh = [self.a, self.alpha, self.d, self.theta];
        if dh.iter().any(|v| !v.is_finite()) {
            return Err(("tool", ConfigReason::NotFinite));
        }
        if self.xyz.iter().any(|v| !v.is_finite()) {
            return Err(("tool.xyz", ConfigReason::NotFinite));
        }
        if self.rpy.iter().any(|v| !v.is_finite()) {
            return Err(("tool.rpy", ConfigReason::NotFinite));
        }
        Ok(())
    }
}

impl IkConfig {
    fn validate(&self) -> Result<(), (&'static str, ConfigReason)> {
        positive(self.tolerance).map_err(|r| ("ik.tolerance", r))?;
        if !(1..=MAX_TRACKING_ITERATIONS).contains(&self.tracking_iterations) {
            return Err(("ik.tracking_iterations", ConfigReason::TrackingIterations));
        }
        if self.global_iterations == 0 {
            return Err(("ik.global_iterations", ConfigReason::NotPositive));
        }
        if !(1.0..=MAX_LINE_SLOWDOWN).contains(&self.line_slowdown) {
            return Err(("ik.line_slowdown", ConfigReason::LineSlowdown));
        }
        Ok(())
    }
}

pub(super) fn not_negative(v: f64) -> Result<(), ConfigReason> {
    finite(v)?;
    if v < 0.0 {
        Err(ConfigReason::Negative)
    } else {
        Ok(())
    }
}

fn finite(v: f64) -> Result<(), ConfigReason> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(ConfigReason::NotFinite)
    }
}

fn positive(v: f64) -> Result<(), ConfigReason> {
    finite(v)?;
    if v > 0.0 {
        Ok(())
    } else {
        Err(ConfigReason::NotPositive)
    }
}

/// A box `[x_min, x_max, y_min, y_max, z_min, z_max]` must be finite with min ≤ max per axis.
fn check_box(b: &[f64; 6]) -> Result<(), ConfigReason> {
    for pair in b.chunks_exact(2) {
        if let [lo, hi] = pair {
            finite(*lo)?;
            finite(*hi)?;
            if lo > hi {
                return Err(ConfigReason::MinAboveMax);
            }
        }
    }
    Ok(())
}
