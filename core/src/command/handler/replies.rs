//! The handler's replies and refusal texts: how a controller refusal, an IK error or the
//! drives' state becomes the client's `ER` text, and how values become a reply.

use armgate_protocol::client::banks::READ_JOINTS;
use armgate_protocol::client::{
    Command, DriveStatus, Notice, Rejection, Reply, VALUES, WorkspaceReason,
};

use crate::command::banks::{BANK_2, BANK_LEN};
use crate::command::drives::Drives;
use crate::command::ik::IkRequestError;
use crate::motion::{Mode, Refusal};

/// The client text for a refused request, with its reason. (Out of line: eleven callers, all
/// answering requests.)
#[inline(never)]
pub(super) fn refusal_notice(cmd: Command, refusal: Refusal) -> Notice {
    let rejected = |why| Notice::Rejected(cmd, why);
    let workspace = |why| Notice::OutsideWorkspace(cmd, why);
    match refusal {
        Refusal::InvalidNumber | Refusal::WrongJointCount => Notice::BadNumber(cmd),
        Refusal::IndexOutOfRange => Notice::BadIndex(cmd),
        Refusal::OutsideWorkspace => workspace(WorkspaceReason::Goal),
        Refusal::CrossesBox(percent) => workspace(WorkspaceReason::CrossesBox(percent)),
        Refusal::Unreachable(at) => workspace(WorkspaceReason::Unreachable(at)),
        Refusal::ArmOutsideWorkspace => workspace(WorkspaceReason::ArmOutside),
        Refusal::TooFast(joint, at) => workspace(WorkspaceReason::TooFast(joint, at)),
        Refusal::NearEdge(at) => workspace(WorkspaceReason::NearEdge(at)),
        Refusal::Hits(hit, at) => workspace(WorkspaceReason::Hits(hit, at)),
        Refusal::OutsideJointLimits(bound) => Notice::BeyondJointLimit(cmd, bound),
        Refusal::NoGoal => rejected(match cmd {
            Command::ViaExecute | Command::JointExecute => Rejection::NoViaPoint,
            _ => Rejection::NoGoal,
        }),
        // Only the requests that need a mode are refused for the wrong one.
        Refusal::WrongMode => rejected(Rejection::NeedsMode(
            Mode::required_by(cmd).unwrap_or_default(),
        )),
        Refusal::Busy => rejected(Rejection::Busy),
        Refusal::NotReady => rejected(Rejection::NoMeasurement),
        Refusal::Stopped(cause) => rejected(Rejection::Stopped(cause)),
    }
}

/// The client text for a refused `KG`/`KS`.
pub(super) fn ik_notice(cmd: Command, error: IkRequestError) -> Notice {
    match error {
        IkRequestError::BadNumber => Notice::BadNumber(cmd),
        IkRequestError::BadIndex => Notice::BadIndex(cmd),
        IkRequestError::BranchBeyondLimits => Notice::BranchBeyondLimits(cmd),
        IkRequestError::Refused(r) => refusal_notice(cmd, r),
    }
}

pub(super) fn no_measurement(cmd: Command) -> Notice {
    Notice::Rejected(cmd, Rejection::NoMeasurement)
}

/// Motion needs running drives; otherwise the reason is their state, or their fault.
pub(super) fn operational(drives: &(impl Drives + ?Sized), cmd: Command) -> Result<(), Notice> {
    let why = match (drives.status(), drives.fault_code()) {
        (DriveStatus::Running, _) => return Ok(()),
        (_, Some(code)) => Rejection::DriveFault(code),
        (status, None) => Rejection::Drives(status),
    };
    Err(Notice::Rejected(cmd, why))
}

/// Why the drives refused `RC`: busy means starting, stopping, or still executing the last
/// set-points after the mode was switched off (settling).
pub(super) fn recalibration_refused(refusal: Refusal, status: DriveStatus) -> Notice {
    let cmd = Command::Recalibrate;
    match (refusal, status) {
        (Refusal::Busy, DriveStatus::Starting | DriveStatus::Stopping) => {
            Notice::Rejected(cmd, Rejection::Drives(status))
        }
        (Refusal::Busy, _) => Notice::Rejected(cmd, Rejection::DrivesSettling),
        (other, _) => refusal_notice(cmd, other),
    }
}

/// The six joint values of a joint request, all finite.
pub(super) fn bank_values(v: &[f64; VALUES], cmd: Command) -> Result<&[f64], Notice> {
    let joints = v.get(..BANK_LEN).unwrap_or(&[]);
    if joints.iter().all(|x| x.is_finite()) {
        Ok(joints)
    } else {
        Err(Notice::BadNumber(cmd))
    }
}

/// A duration: finite, negative ones clamped to 0 (the seed left jV/VP unclamped, §9 item 12).
pub(super) fn non_negative(t: f64) -> Option<f64> {
    t.is_finite().then_some(t.max(0.0))
}

/// The reply to a motion start (`BG`, `jB`): f6 the planned duration (s), the rest 0.
pub(super) fn planned_reply(cmd: Command, planned: f64) -> Reply {
    values_reply(cmd, &[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, planned], 0)
}

/// A reply carrying `values` in f0.. (the rest zero).
pub(super) fn values_reply(cmd: Command, values: &[f64], index: u8) -> Reply {
    let mut out = [0.0f32; VALUES];
    for (o, v) in out.iter_mut().zip(values) {
        *o = *v as f32;
    }
    Reply {
        command: cmd,
        values: out,
        index,
    }
}

/// jP/TM: joints 1–7 in f0..f6, or joints 7.. for bank 2 (refused on an arm without them,
/// as docs/protocol.md says); unused slots hold `pad`.
pub(super) fn joint_reply(
    cmd: Command,
    q: &[f64],
    bank_2: bool,
    n: usize,
    pad: f32,
) -> Result<Reply, Notice> {
    if bank_2 && n <= BANK_LEN {
        return Err(Notice::BadIndex(cmd));
    }
    let skip = if bank_2 { BANK_LEN } else { 0 };
    let mut values = [pad; VALUES];
    for (o, v) in values
        .iter_mut()
        .zip(q.iter().take(n).skip(skip))
        .take(READ_JOINTS)
    {
        *o = *v as f32;
    }
    Ok(Reply {
        command: cmd,
        values,
        index: if bank_2 { BANK_2 } else { 0 },
    })
}
