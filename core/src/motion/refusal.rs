//! Why a motion request was refused.

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
    /// A joint goal lies outside the joint limits.
    OutsideJointLimits,
    /// A Cartesian goal lies outside the workspace bounds or inside an exclusion box, or the
    /// arm itself is in a forbidden region (drive it out in joint mode).
    OutsideWorkspace,
    /// A via-point index is not below the number of slots.
    IndexOutOfRange,
    /// The controller has not yet received a measurement.
    NotReady,
}

impl core::fmt::Display for Refusal {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::NoGoal => "no goal or via point 0",
            Self::WrongMode => "wrong control mode",
            Self::Busy => "a motion or sequence is running",
            Self::InvalidNumber => "invalid number",
            Self::WrongJointCount => "wrong number of joint values",
            Self::OutsideJointLimits => "goal outside the joint limits",
            Self::OutsideWorkspace => "outside the workspace",
            Self::IndexOutOfRange => "via-point index out of range",
            Self::NotReady => "no measurement yet",
        })
    }
}
