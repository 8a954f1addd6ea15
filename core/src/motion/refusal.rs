//! Why a motion request was refused.

use armgate_protocol::client::{Hit, JointBound, PathPoint, StopCause};

/// Why the controller refused a request; the command handler maps each to an `ER` reply.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Refusal {
    /// There is nothing to move to: no goal, or no via point 0 for a sequence.
    NoGoal,
    /// The request needs another control mode (e.g. a Cartesian move in joint mode).
    WrongMode,
    /// A motion or a sequence is still running.
    Busy,
    /// A number is NaN or infinite, or out of its domain (e.g. a zero radius).
    InvalidNumber,
    /// The joint vector does not have one value per joint.
    WrongJointCount,
    /// A joint goal, or a point on the way to a Cartesian goal, lies beyond this joint limit.
    OutsideJointLimits(JointBound),
    /// A Cartesian goal lies outside the workspace bounds or inside an exclusion box.
    OutsideWorkspace,
    /// The straight line to a Cartesian goal enters an exclusion box at this percentage of
    /// the way.
    CrossesBox(u8),
    /// No joint configuration within the limits follows the straight line to a Cartesian goal
    /// from the current one at this point (out of reach, or a singularity).
    Unreachable(PathPoint),
    /// Joint N (1-based) would need more than its rate limit at this point of the straight
    /// line to a Cartesian goal at the planned speed (a jump to another IK branch, or a
    /// singularity).
    TooFast(u8, PathPoint),
    /// A joint move's way comes so near a box or the bounds at this point that the check
    /// cannot tell within its work budget that it stays clear (`joint_path.rs`).
    NearEdge(PathPoint),
    /// The arm itself is in a forbidden region (drive it out in joint mode).
    ArmOutsideWorkspace,
    /// A link of the arm would hit a box, another link or the bounds at this point of the
    /// way (its capsule within the margin).
    Hits(Hit, PathPoint),
    /// A via-point index is not below the number of slots.
    IndexOutOfRange,
    /// The controller has not yet received a measurement.
    NotReady,
    /// A stream after this stop, which latched: only a zero twist or zero joint rates (or a
    /// move) starts motion again.
    Stopped(StopCause),
}

impl core::fmt::Display for Refusal {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NoGoal => f.write_str("no goal or via point 0"),
            Self::WrongMode => f.write_str("wrong control mode"),
            Self::Busy => f.write_str("a motion or sequence is running"),
            Self::InvalidNumber => f.write_str("invalid number"),
            Self::WrongJointCount => f.write_str("wrong number of joint values"),
            Self::OutsideJointLimits(bound) => write!(f, "beyond a joint limit: {bound}"),
            Self::OutsideWorkspace => f.write_str("outside the workspace"),
            Self::CrossesBox(percent) => {
                write!(f, "the line enters an exclusion box at {percent}%")
            }
            Self::Unreachable(PathPoint::Goal) => f.write_str("goal out of reach"),
            Self::Unreachable(PathPoint::Along(percent)) => {
                write!(f, "out of reach at {percent}% of the line")
            }
            Self::TooFast(joint, PathPoint::Goal) => {
                write!(f, "joint {joint} too fast at the goal")
            }
            Self::TooFast(joint, PathPoint::Along(percent)) => {
                write!(f, "joint {joint} too fast at {percent}% of the line")
            }
            Self::NearEdge(PathPoint::Goal) => f.write_str("too near a box or bound at the goal"),
            Self::NearEdge(PathPoint::Along(percent)) => {
                write!(f, "too near a box or bound at {percent}% of the way")
            }
            Self::ArmOutsideWorkspace => f.write_str("the arm is outside the workspace"),
            Self::Hits(hit, PathPoint::Goal) => write!(f, "{hit} at the goal"),
            Self::Hits(hit, PathPoint::Along(percent)) => {
                write!(f, "{hit} at {percent}% of the way")
            }
            Self::IndexOutOfRange => f.write_str("via-point index out of range"),
            Self::NotReady => f.write_str("no measurement yet"),
            Self::Stopped(cause) => {
                write!(f, "stopped ({cause:?}): a zero velocity re-arms the stream")
            }
        }
    }
}
