//! The calibration model: a robot's geometry as named parameters, and the tool position as a
//! function of them.
//!
//! The transform is the one `armgate_core::kinematics::Chain` evaluates (a test checks that they
//! agree): `Base · Π RotX(α)·TransX(a)·RotY(β)·RotZ(θ)·TransZ(d) · Tool`, with the joint variable
//! added to θ (revolute) or d (prismatic). Here every constant is a variable that can be fitted.
//! The instrument sees that position in its own frame, through one more rigid transform: the
//! robot's world frame in the instrument's, which calibration fits as well.

use std::fmt;

use armgate_core::config::{JointType, RobotConfig};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

/// Consecutive axes closer to parallel than this (rad) get Hayati's β: their common normal, and
/// with it the DH `d`, is ill-defined.
pub const NEARLY_PARALLEL: f64 = 10.0 * std::f64::consts::PI / 180.0;

/// One geometric constant that calibration may fit. Joint indices count from 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Param {
    /// `[base] xyz[k]` (m).
    BaseXyz(usize),
    /// `[base] rpy[k]` (rad).
    BaseRpy(usize),
    /// `theta` of joint i (rad); the joint offset of a revolute joint.
    Theta(usize),
    /// `d` of joint i (m); the joint offset of a prismatic joint.
    D(usize),
    /// `a` of joint i, a_{i-1} (m).
    A(usize),
    /// `alpha` of joint i, α_{i-1} (rad).
    Alpha(usize),
    /// `beta` of joint i, Hayati's β_{i-1} (rad).
    Beta(usize),
    /// `[tool] xyz[k]` (m).
    ToolXyz(usize),
    /// A correction to the instrument's frame, applied in the robot's world frame: k = 0..3 a
    /// translation (m), k = 3..6 a rotation vector (rad). Fitted from 0 after the registration;
    /// parametrised at the robot, not at the instrument, so that the identification Jacobian
    /// (and the condition number) does not depend on where the instrument stands.
    Instrument(usize),
}

impl Param {
    /// True for angles (rad), false for lengths (m).
    pub fn is_angle(self) -> bool {
        matches!(
            self,
            Self::BaseRpy(_) | Self::Theta(_) | Self::Alpha(_) | Self::Beta(_)
        ) || matches!(self, Self::Instrument(k) if k >= 3)
    }

    /// True for the parameters of the instrument's frame (not the robot's).
    pub fn is_instrument(self) -> bool {
        matches!(self, Self::Instrument(_))
    }

    /// The unit the report prints the parameter in, and the factor from SI to it.
    pub fn display_unit(self) -> (&'static str, f64) {
        if self.is_angle() {
            ("deg", 180.0 / std::f64::consts::PI)
        } else {
            ("mm", 1000.0)
        }
    }
}

impl fmt::Display for Param {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const XYZ: [&str; 3] = ["x", "y", "z"];
        const RPY: [&str; 3] = ["roll", "pitch", "yaw"];
        let axis = |names: [&'static str; 3], k: usize| names.get(k).copied().unwrap_or("?");
        match *self {
            Self::BaseXyz(k) => write!(f, "base.{}", axis(XYZ, k)),
            Self::BaseRpy(k) => write!(f, "base.{}", axis(RPY, k)),
            Self::Theta(i) => write!(f, "J{}.theta", i + 1),
            Self::D(i) => write!(f, "J{}.d", i + 1),
            Self::A(i) => write!(f, "J{}.a", i + 1),
            Self::Alpha(i) => write!(f, "J{}.alpha", i + 1),
            Self::Beta(i) => write!(f, "J{}.beta", i + 1),
            Self::ToolXyz(k) => write!(f, "tool.{}", axis(XYZ, k)),
            Self::Instrument(k) if k < 3 => write!(f, "instrument.{}", axis(XYZ, k)),
            Self::Instrument(k) => write!(f, "instrument.r{}", axis(XYZ, k - 3)),
        }
    }
}

/// The names of `params`, comma-separated ("none" for none): how reports list them.
pub fn list(params: &[Param]) -> String {
    if params.is_empty() {
        return "none".into();
    }
    let names: Vec<String> = params.iter().map(ToString::to_string).collect();
    names.join(", ")
}

/// Which parameters a calibration may fit.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum FitSet {
    /// Joint offsets, DH lengths and angles, Hayati angles, base and tool position.
    #[default]
    All,
    /// Joint offsets only (the seed's experiment E3 (a)).
    Offsets,
    /// DH lengths and the tool position only, offsets held (the seed's E3 (b)).
    Lengths,
}

/// The frame the measured positions are in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum MeasuredIn {
    /// The instrument's own frame, wherever it stands: its placement is fitted too.
    #[default]
    Instrument,
    /// The robot file's world frame (the instrument registered to the robot's world beforehand,
    /// as the seed's Faro arm was): no instrument frame is fitted; joint 1's constants and what
    /// they leave of the `[base]` are.
    World,
}

/// One link's constants.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Link {
    prismatic: bool,
    alpha: f64,
    beta: f64,
    a: f64,
    d: f64,
    theta: f64,
}

/// A robot's geometry with every constant free: what calibration fits.
#[derive(Clone, Debug, PartialEq)]
pub struct Geometry {
    base_xyz: [f64; 3],
    base_rpy: [f64; 3],
    links: Vec<Link>,
    /// The tool's DH part and orientation; only the position matters to the measurements.
    tool_dh: Isometry3<f64>,
    tool_rpy: [f64; 3],
    tool_xyz: [f64; 3],
    /// The robot's world frame in the instrument's (registration), before the correction.
    instrument: Isometry3<f64>,
    /// The fitted correction [`Param::Instrument`].
    instrument_correction: [f64; 6],
}

impl Geometry {
    /// The geometry a robot description states.
    pub fn new(config: &RobotConfig) -> Self {
        let links = config
            .joints
            .iter()
            .map(|j| Link {
                prismatic: j.kind == JointType::Prismatic,
                alpha: j.alpha,
                beta: j.beta,
                a: j.a,
                d: j.d,
                theta: j.theta,
            })
            .collect();
        let t = &config.tool;
        Self {
            base_xyz: config.base.xyz,
            base_rpy: config.base.rpy,
            links,
            tool_dh: link_transform(t.alpha, 0.0, t.a, t.theta, t.d),
            tool_rpy: t.rpy,
            tool_xyz: t.xyz,
            instrument: Isometry3::identity(),
            instrument_correction: [0.0; 6],
        }
    }

    /// A copy seen by an instrument whose frame holds the robot's world frame at `registration`
    /// (maps world coordinates to instrument coordinates), with no correction.
    pub fn registered(&self, registration: Isometry3<f64>) -> Self {
        Self {
            instrument: registration,
            instrument_correction: [0.0; 6],
            ..self.clone()
        }
    }

    /// The robot's world frame in the instrument's frame, correction included: instrument
    /// coordinates = this · world coordinates.
    pub fn instrument(&self) -> Isometry3<f64> {
        let [x, y, z, rx, ry, rz] = self.instrument_correction;
        self.instrument * Isometry3::new(Vector3::new(x, y, z), Vector3::new(rx, ry, rz))
    }

    /// The `[base]` frame: the robot's base {0} in its world frame.
    pub fn base(&self) -> Isometry3<f64> {
        let [roll, pitch, yaw] = self.base_rpy;
        Isometry3::from_parts(
            Translation3::from(Vector3::from(self.base_xyz)),
            UnitQuaternion::from_euler_angles(roll, pitch, yaw),
        )
    }

    /// A copy whose `[base]` is `base` (translation and roll, pitch, yaw).
    pub fn with_base(&self, base: &Isometry3<f64>) -> Self {
        let (roll, pitch, yaw) = base.rotation.euler_angles();
        Self {
            base_xyz: base.translation.vector.into(),
            base_rpy: [roll, pitch, yaw],
            ..self.clone()
        }
    }
    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.links.len()
    }

    /// The value of one parameter (0 for a parameter this robot does not have).
    pub fn get(&self, p: Param) -> f64 {
        let link = |i: usize| self.links.get(i);
        let value = match p {
            Param::BaseXyz(k) => self.base_xyz.get(k),
            Param::BaseRpy(k) => self.base_rpy.get(k),
            Param::ToolXyz(k) => self.tool_xyz.get(k),
            Param::Instrument(k) => self.instrument_correction.get(k),
            Param::Theta(i) => link(i).map(|l| &l.theta),
            Param::D(i) => link(i).map(|l| &l.d),
            Param::A(i) => link(i).map(|l| &l.a),
            Param::Alpha(i) => link(i).map(|l| &l.alpha),
            Param::Beta(i) => link(i).map(|l| &l.beta),
        };
        value.copied().unwrap_or(0.0)
    }

    /// Sets one parameter (ignored for a parameter this robot does not have).
    pub fn set(&mut self, p: Param, value: f64) {
        let slot = match p {
            Param::BaseXyz(k) => self.base_xyz.get_mut(k),
            Param::BaseRpy(k) => self.base_rpy.get_mut(k),
            Param::ToolXyz(k) => self.tool_xyz.get_mut(k),
            Param::Instrument(k) => self.instrument_correction.get_mut(k),
            Param::Theta(i) => self.links.get_mut(i).map(|l| &mut l.theta),
            Param::D(i) => self.links.get_mut(i).map(|l| &mut l.d),
            Param::A(i) => self.links.get_mut(i).map(|l| &mut l.a),
            Param::Alpha(i) => self.links.get_mut(i).map(|l| &mut l.alpha),
            Param::Beta(i) => self.links.get_mut(i).map(|l| &mut l.beta),
        };
        if let Some(slot) = slot {
            *slot = value;
        }
    }

    /// The values of `params`.
    pub fn values(&self, params: &[Param]) -> Vec<f64> {
        params.iter().map(|&p| self.get(p)).collect()
    }

    /// A copy with `params` set to `values`.
    pub fn with(&self, params: &[Param], values: &[f64]) -> Self {
        let mut g = self.clone();
        for (&p, &v) in params.iter().zip(values) {
            g.set(p, v);
        }
        g
    }

    /// The tool position in the instrument's frame at joint values `q` (one per joint): what
    /// the instrument measures.
    pub fn position(&self, q: &[f64]) -> Vector3<f64> {
        self.instrument()
            .transform_point(&self.robot_position(q).into())
            .coords
    }

    /// The tool position in the robot's world frame (as the controller computes it).
    pub fn robot_position(&self, q: &[f64]) -> Vector3<f64> {
        let mut frame = self.base();
        for (link, &qi) in self.links.iter().zip(q) {
            let (theta, d) = if link.prismatic {
                (link.theta, link.d + qi)
            } else {
                (link.theta + qi, link.d)
            };
            frame *= link_transform(link.alpha, link.beta, link.a, theta, d);
        }
        let tool_origin = frame * self.tool_dh;
        tool_origin
            .transform_point(&Vector3::from(self.tool_xyz).into())
            .coords
    }

    /// Joints whose axis is nearly parallel to the previous one (Hayati's β is fitted there
    /// instead of relying on `d`). The first joint is never one: the base frame's roll and pitch
    /// take that role.
    pub fn nearly_parallel(&self) -> Vec<usize> {
        (1..self.dof())
            .filter(|&i| {
                self.links
                    .get(i)
                    .is_some_and(|l| l.alpha.sin().abs() < NEARLY_PARALLEL.sin() || l.beta != 0.0)
            })
            .collect()
    }

    /// The parameters a calibration of `set` may fit, most meaningful first: where parameters
    /// are redundant, identifiability analysis keeps the earlier one. The instrument's frame
    /// comes first: it takes whatever the robot's base frame and joint 1's constants could
    /// also explain (the `[base]` frame is not a candidate at all, and joint 1's offset, `d`,
    /// `a` and `alpha` stay nominal), so the robot's constants stay relative to its own base.
    /// Then the robot's [`constants`](Self::constants) in their order. Measured in the world
    /// frame there is no instrument frame: the candidates are the constants, the `[base]` (the
    /// robot's place in that world) last.
    pub fn candidates(&self, set: FitSet, measured_in: MeasuredIn) -> Vec<Param> {
        match measured_in {
            MeasuredIn::World => self.constants(set),
            MeasuredIn::Instrument => (0..6)
                .map(Param::Instrument)
                .chain(
                    self.constants(set)
                        .into_iter()
                        .filter(|p| !matches!(p, Param::BaseXyz(_) | Param::BaseRpy(_))),
                )
                .collect(),
        }
    }

    /// The robot file's constants of `set`: joint offsets first, then DH lengths and the tool
    /// position, DH angles, Hayati angles and last the base frame.
    pub fn constants(&self, set: FitSet) -> Vec<Param> {
        let n = self.dof();
        let offset = |i: usize| {
            if self.links.get(i).is_some_and(|l| l.prismatic) {
                Param::D(i)
            } else {
                Param::Theta(i)
            }
        };
        let length = |i: usize| {
            if self.links.get(i).is_some_and(|l| l.prismatic) {
                None
            } else {
                Some(Param::D(i))
            }
        };
        let offsets = (0..n).map(offset);
        // A prismatic joint's constant θ is a DH angle like α.
        let prismatic_angles = (0..n)
            .filter(|&i| self.links.get(i).is_some_and(|l| l.prismatic))
            .map(Param::Theta);
        let lengths = (0..n)
            .flat_map(|i| [Some(Param::A(i)), length(i)])
            .flatten()
            .chain((0..3).map(Param::ToolXyz));
        match set {
            FitSet::Offsets => offsets.collect(),
            FitSet::Lengths => lengths.collect(),
            FitSet::All => offsets
                .chain(lengths)
                .chain((0..n).map(Param::Alpha))
                .chain(prismatic_angles)
                .chain(self.nearly_parallel().into_iter().map(Param::Beta))
                .chain((0..3).map(Param::BaseXyz))
                .chain((0..3).map(Param::BaseRpy))
                .collect(),
        }
    }

    /// Writes the geometry into a robot description (the inverse of [`Geometry::new`] for
    /// everything calibration fits).
    pub fn apply_to(&self, config: &mut RobotConfig) {
        config.base.xyz = self.base_xyz;
        config.base.rpy = self.base_rpy;
        config.tool.xyz = self.tool_xyz;
        config.tool.rpy = self.tool_rpy;
        for (joint, link) in config.joints.iter_mut().zip(&self.links) {
            joint.alpha = link.alpha;
            joint.beta = link.beta;
            joint.a = link.a;
            joint.d = link.d;
            joint.theta = link.theta;
        }
    }
}

/// `RotX(α) · TransX(a) · RotY(β) · RotZ(θ) · TransZ(d)`.
fn link_transform(alpha: f64, beta: f64, a: f64, theta: f64, d: f64) -> Isometry3<f64> {
    let rot_x = Isometry3::rotation(Vector3::x() * alpha);
    let trans_x = Isometry3::translation(a, 0.0, 0.0);
    let rot_y = Isometry3::rotation(Vector3::y() * beta);
    let rot_z = Isometry3::rotation(Vector3::z() * theta);
    let trans_z = Isometry3::translation(0.0, 0.0, d);
    rot_x * trans_x * rot_y * rot_z * trans_z
}
