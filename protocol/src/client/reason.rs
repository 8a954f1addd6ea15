//! Why a request was refused: the typed reasons that follow `ERnn Cmd XX` in a refusal text.
//!
//! Every text must fit [`TEXT_CAPACITY`](super::TEXT_CAPACITY) = 30 characters, and the
//! `ERnn Cmd XX ` prefix takes 12, so the wording is compact (docs/protocol.md lists them all).

use core::fmt;

use super::words::{Milli, decimal, phrase, value_of};
use super::{Hit, Mode, StopCause};

/// The drives' state, as a status reply (`QS` f1) and refusals report it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DriveStatus {
    /// Never started, or stopped on request (`OF`).
    Off = 0,
    /// Being brought up after `ON` (or at power-up).
    Starting = 1,
    /// Set-points reach the joints: motion is possible. (A simulated arm without drives is
    /// running while it is on.)
    Running = 2,
    /// Coming to rest after `OF` or a fault.
    Stopping = 3,
    /// Stopped by a drive fault (its `ER3x` code is reported alongside).
    Faulted = 4,
}

impl DriveStatus {
    /// Every state, by code.
    pub const ALL: [Self; 5] = [
        Self::Off,
        Self::Starting,
        Self::Running,
        Self::Stopping,
        Self::Faulted,
    ];

    /// The state with this code.
    pub fn from_code(code: u8) -> Option<Self> {
        Self::ALL.into_iter().find(|s| *s as u8 == code)
    }
}

/// Why a request was refused with `ER20`: the text after `ER20 Cmd XX `.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Rejection {
    /// `busy`: a motion or sequence is running (send `ST` first).
    Busy,
    /// `drives starting` / `drives off` / `drives stopping`: the drives take no set-points in
    /// this state (never [`DriveStatus::Running`] or [`DriveStatus::Faulted`]).
    Drives(DriveStatus),
    /// `drive fault NN`: the drives were stopped by the fault `ERNN` (send `ON` to restart).
    DriveFault(u8),
    /// `drives settling`: `RC` while the drives still execute the last set-points (the mode was
    /// just switched off); retry a few ticks later.
    DrivesSettling,
    /// `needs mode N`: the request needs control mode N (0 off, 1 joint, 2 Cartesian).
    NeedsMode(Mode),
    /// `no goal`: `BG` without a `GL`/`GT`, `jB` without a `jG`.
    NoGoal,
    /// `no via point 0`: `VE`/`jE` with via slot 0 empty.
    NoViaPoint,
    /// `no measurement`: the controller has not measured the joints yet.
    NoMeasurement,
    /// `holder changed`: `BG`/`jB` without a goal, `VE`/`jE` without via points, because
    /// another client took control since this one set them: goals, via points and blends
    /// belong to the client that set them, and a new holder starts with none.
    HolderChanged,
    /// `after ST: send 0`: a stream (`TW`, `jW`) after a stop, which latches: the arm stays
    /// at rest until the holder starts a motion on purpose, a zero twist or zero joint rates
    /// (which re-arm the stream) or a move. Names the stop (`ST`, `OF`, `ER21`, `WN22`, `ER41`).
    Stopped(StopCause),
}

impl Rejection {
    /// The reasons that are one fixed phrase.
    const PHRASES: [(Self, &'static str); 11] = [
        (Self::Busy, "busy"),
        (Self::Drives(DriveStatus::Off), "drives off"),
        (Self::Drives(DriveStatus::Starting), "drives starting"),
        (Self::Drives(DriveStatus::Running), "drives on"),
        (Self::Drives(DriveStatus::Stopping), "drives stopping"),
        (Self::Drives(DriveStatus::Faulted), "drive fault"),
        (Self::DrivesSettling, "drives settling"),
        (Self::NoGoal, "no goal"),
        (Self::NoViaPoint, "no via point 0"),
        (Self::NoMeasurement, "no measurement"),
        (Self::HolderChanged, "holder changed"),
    ];
    const DRIVE_FAULT: &'static str = "drive fault ";
    const NEEDS_MODE: &'static str = "needs mode ";
    /// `after <stop>: send 0`.
    const STOPPED: (&'static str, &'static str) = ("after ", ": send 0");

    /// Reads the reason back from the text after `ER20 Cmd XX `.
    pub(super) fn parse(s: &str) -> Option<Self> {
        if let Some(fixed) = value_of(&Self::PHRASES, s) {
            return Some(fixed);
        }
        if let Some(code) = s.strip_prefix(Self::DRIVE_FAULT) {
            return decimal(code).map(Self::DriveFault);
        }
        if let Some(name) = s
            .strip_prefix(Self::STOPPED.0)
            .and_then(|r| r.strip_suffix(Self::STOPPED.1))
        {
            let cause = StopCause::ALL.into_iter().find(|c| stop_name(*c) == name);
            return cause.map(Self::Stopped);
        }
        let mode: u8 = decimal(s.strip_prefix(Self::NEEDS_MODE)?)?;
        let mode = Mode::ALL.into_iter().find(|m| m.value() == mode)?;
        Some(Self::NeedsMode(mode))
    }
}

impl fmt::Display for Rejection {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::DriveFault(code) => write!(f, "{}{code:02}", Self::DRIVE_FAULT),
            Self::NeedsMode(mode) => write!(f, "{}{}", Self::NEEDS_MODE, mode.value()),
            Self::Stopped(cause) => {
                let (before, after) = Self::STOPPED;
                write!(f, "{before}{}{after}", stop_name(cause))
            }
            fixed => f.write_str(phrase(&Self::PHRASES, &fixed).unwrap_or_default()),
        }
    }
}

/// A stop's short name in a refusal (`after ST: send 0`): the request or notice that caused
/// it, at most four characters so that every text fits.
fn stop_name(cause: StopCause) -> &'static str {
    match cause {
        StopCause::Stop => "ST",
        StopCause::ModeChange => "CM",
        StopCause::PowerOff => "OF",
        StopCause::Workspace => "ER21",
        StopCause::IkDivergence => "WN22",
        StopCause::StreamTimeout => "idle",
        StopCause::JointLimit => "WN12",
        StopCause::ClientSilent => "ER41",
        StopCause::FollowingError => "ER43",
    }
}

/// Where along a Cartesian move a problem lies: the goal itself, or a point on the straight
/// line to it, in percent of the way (1..=99).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PathPoint {
    /// The goal (or the via point) itself.
    Goal,
    /// This percentage of the way there.
    Along(u8),
}

impl PathPoint {
    /// The point at `fraction` (0..1) of the way; 1 and beyond is the goal, and a point short
    /// of the goal never rounds up to 100 %.
    pub fn at(fraction: f64) -> Self {
        if fraction >= 1.0 {
            return Self::Goal;
        }
        // Saturating float-to-int casts: NaN and negatives become 0.
        Self::Along((fraction * 100.0) as u8).min_one()
    }

    /// Splits ` at NN%` off the end of `s`: the rest and the point (the goal without one).
    fn split(s: &str) -> Option<(&str, Self)> {
        match s.strip_suffix('%').and_then(|r| r.rsplit_once(Self::AT)) {
            Some((head, percent)) => Some((head, Self::Along(decimal(percent)?))),
            None => Some((s, Self::Goal)),
        }
    }

    const AT: &'static str = " at ";

    fn min_one(self) -> Self {
        match self {
            Self::Along(0) => Self::Along(1),
            Self::Along(p) if p > 99 => Self::Along(99),
            other => other,
        }
    }
}

/// ` at NN%` after a path point, nothing after the goal.
struct At(PathPoint);

impl fmt::Display for At {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            PathPoint::Goal => Ok(()),
            PathPoint::Along(percent) => write!(f, "{}{percent}%", PathPoint::AT),
        }
    }
}

/// Why a Cartesian goal is refused with `ER25`: the text after `ER25 Cmd XX `.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum WorkspaceReason {
    /// `outside workspace`: the goal lies outside the bounds or inside an exclusion box.
    Goal,
    /// `crosses box at NN%`: the straight line to the goal crosses an exclusion box.
    CrossesBox(u8),
    /// `unreachable` / `unreachable at NN%`: no joint configuration within the limits reaches
    /// that pose continuously from the current one (beyond the arm's reach, or a singularity).
    Unreachable(PathPoint),
    /// `arm outside`: the arm itself is outside the workspace (drive it back in joint mode).
    ArmOutside,
    /// `jN too fast at NN%`: joint N would need more than its rate limit there at the
    /// planned speed (the IK solution jumps to another branch, or a singularity).
    TooFast(u8, PathPoint),
    /// `near edge at NN%`: a joint move's way comes so near an exclusion box or the bounds
    /// there that the check, within its work budget, cannot tell that it stays clear.
    NearEdge(PathPoint),
    /// `L3 hits B1 at 40%`, `L5 hits L2`, `L3 out at 99%`: a link of the arm (its capsule,
    /// inflated by what it may sweep between checked samples) would come within the margin of
    /// a box, another link or the bounds there (docs/safety.md).
    Hits(Hit, PathPoint),
}

impl WorkspaceReason {
    /// The reasons that are one fixed phrase.
    const PHRASES: [(Self, &'static str); 2] = [
        (Self::Goal, "outside workspace"),
        (Self::ArmOutside, "arm outside"),
    ];
    const CROSSES_BOX: &'static str = "crosses box at ";
    const UNREACHABLE: &'static str = "unreachable";
    const TOO_FAST: &'static str = " too fast";
    const NEAR_EDGE: &'static str = "near edge";

    /// Reads the reason back from the text after `ER25 Cmd XX `.
    pub(super) fn parse(s: &str) -> Option<Self> {
        if let Some(fixed) = value_of(&Self::PHRASES, s) {
            return Some(fixed);
        }
        if let Some(percent) = s.strip_prefix(Self::CROSSES_BOX) {
            return decimal(percent.strip_suffix('%')?).map(Self::CrossesBox);
        }
        let (head, at) = PathPoint::split(s)?;
        if head == Self::UNREACHABLE {
            return Some(Self::Unreachable(at));
        }
        if head == Self::NEAR_EDGE {
            return Some(Self::NearEdge(at));
        }
        if let Some(hit) = Hit::parse(head) {
            return Some(Self::Hits(hit, at));
        }
        let joint = head.strip_prefix('j')?.strip_suffix(Self::TOO_FAST)?;
        Some(Self::TooFast(decimal(joint)?, at))
    }
}

impl fmt::Display for WorkspaceReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::CrossesBox(percent) => write!(f, "{}{percent}%", Self::CROSSES_BOX),
            Self::Unreachable(at) => write!(f, "{}{}", Self::UNREACHABLE, At(at)),
            Self::TooFast(joint, at) => write!(f, "j{joint}{}{}", Self::TOO_FAST, At(at)),
            Self::NearEdge(at) => write!(f, "{}{}", Self::NEAR_EDGE, At(at)),
            Self::Hits(hit, at) => write!(f, "{hit}{}", At(at)),
            fixed => f.write_str(phrase(&Self::PHRASES, &fixed).unwrap_or_default()),
        }
    }
}

/// Which joint limit a request would cross (`ER26`): `j5 < 0.785` (below its minimum),
/// `j3 > 1.600 at 40%` (above its maximum, on the way to a Cartesian goal).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct JointBound {
    /// The joint, numbered from 1.
    pub joint: u8,
    /// True for the maximum, false for the minimum.
    pub above_max: bool,
    /// The limit in thousandths of a radian (or millimetres), as the text shows it.
    pub limit_milli: i32,
    /// Where on a Cartesian move; [`PathPoint::Goal`] for joint goals.
    pub at: PathPoint,
}

impl JointBound {
    /// The bound of joint `index` (0-based) at `limit` (rad or m), rounded to thousandths.
    pub fn new(index: usize, above_max: bool, limit: f64, at: PathPoint) -> Self {
        // Saturating casts: a joint index beyond 255 or a huge limit cannot occur in a valid
        // robot file, and would only print a clipped number.
        Self {
            joint: u8::try_from(index.saturating_add(1)).unwrap_or(u8::MAX),
            above_max,
            limit_milli: round_half_away(limit * 1000.0) as i32,
            at,
        }
    }
}

impl JointBound {
    /// Reads `j5 < 0.785` / `j3 > 1.600 at 40%` back.
    pub(super) fn parse(s: &str) -> Option<Self> {
        let (head, at) = PathPoint::split(s)?;
        let (joint, rest) = head.strip_prefix('j')?.split_once(' ')?;
        let (side, limit) = rest.split_once(' ')?;
        let above_max = match side {
            ">" => true,
            "<" => false,
            _ => return None,
        };
        Some(Self {
            joint: decimal(joint)?,
            above_max,
            limit_milli: Milli::parse(limit)?.0,
            at,
        })
    }
}

/// `ER43 jN following error E`: how far a joint's measured position was from its command (rad
/// or m) when the controller stopped the arm for it (beyond the robot file's
/// `max_following_error`, which the text leaves out: it would not fit).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Lag {
    /// The joint, numbered from 1.
    pub joint: u8,
    /// The error in thousandths (of a radian, or millimetres), as the text shows it: at most
    /// [`MAX_LAG_MILLI`].
    pub error_milli: i32,
}

/// The largest error a [`Lag`] shows (99.999): every text fits its 30 characters.
pub const MAX_LAG_MILLI: i32 = 99_999;

/// The words between a [`Lag`]'s joint and its error.
const FOLLOWING_ERROR: &str = " following error ";

impl Lag {
    /// Joint `index` (0-based) off by `error` (rad or m) from its command, rounded to
    /// thousandths and shown at most as [`MAX_LAG_MILLI`].
    pub fn new(index: usize, error: f64) -> Self {
        // Saturating casts, as for JointBound (NaN shows as 0).
        let milli = round_half_away(libm::fabs(error) * 1000.0) as i32;
        Self {
            joint: u8::try_from(index.saturating_add(1)).unwrap_or(u8::MAX),
            error_milli: milli.min(MAX_LAG_MILLI),
        }
    }

    /// Reads `jN following error E` back.
    pub(super) fn parse(s: &str) -> Option<Self> {
        let (joint, error) = s.strip_prefix('j')?.split_once(FOLLOWING_ERROR)?;
        Some(Self {
            joint: decimal(joint)?,
            error_milli: Milli::parse(error)?.0,
        })
    }
}

impl fmt::Display for Lag {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "j{}{FOLLOWING_ERROR}{}",
            self.joint,
            Milli(self.error_milli)
        )
    }
}

/// Rounds half away from zero without `std` (the cast then saturates).
fn round_half_away(x: f64) -> f64 {
    if x >= 0.0 { x + 0.5 } else { x - 0.5 }
}

impl fmt::Display for JointBound {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "j{} {} {}{}",
            self.joint,
            if self.above_max { '>' } else { '<' },
            Milli(self.limit_milli),
            At(self.at)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn path_points_never_round_to_the_goal() {
        assert_eq!(PathPoint::at(1.0), PathPoint::Goal);
        assert_eq!(PathPoint::at(0.999), PathPoint::Along(99));
        assert_eq!(PathPoint::at(0.404), PathPoint::Along(40));
        assert_eq!(PathPoint::at(0.001), PathPoint::Along(1));
        assert_eq!(PathPoint::at(f64::NAN), PathPoint::Along(1));
    }

    #[test]
    fn joint_bounds_print_joint_side_limit_and_place() {
        let min = JointBound::new(4, false, 0.785, PathPoint::Goal);
        assert_eq!(min.to_string(), "j5 < 0.785");
        let max = JointBound::new(2, true, 1.6, PathPoint::Along(40));
        assert_eq!(max.to_string(), "j3 > 1.600 at 40%");
        let negative = JointBound::new(0, false, -0.0004, PathPoint::Goal);
        assert_eq!(negative.to_string(), "j1 < 0.000");
        let negative = JointBound::new(7, false, -2.3504, PathPoint::Along(99));
        assert_eq!(negative.to_string(), "j8 < -2.350 at 99%");
    }

    #[test]
    fn drive_status_codes_round_trip() {
        for s in DriveStatus::ALL {
            assert_eq!(DriveStatus::from_code(s as u8), Some(s));
        }
        assert_eq!(DriveStatus::from_code(5), None);
    }
}

/// Why a velocity stream holds the arm where the client's command would drive it on: the
/// detail of a `WN12`/`WN13` notice, sent once when the hold begins.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Hold {
    /// `WN12 jN at limit L`: joint N is held at the margin before its limit L (rad or m).
    JointLimit(JointBound),
    /// `WN13 Held at workspace edge.`: the tool would leave the workspace or enter a box.
    Workspace,
    /// `WN13 Held: L3 hits B1`: a link would come to rest within the margin of a box, another
    /// link or the bounds (issue 35); the link and what it would hit are named.
    Contact(Hit),
}
