"""armgate: a Python client for the armgate arm controller.

    import armgate

    with armgate.Arm("127.0.0.1", port=7031) as arm:
        arm.set_mode("cartesian")
        pose = arm.get_tcp_pose()
        arm.move_l(armgate.Pose.from_rpy(pose.x, pose.y, pose.z + 0.05, *pose.rpy), time=2.0)

Standard library only. See README.md and docs/protocol.md of the armgate repository.
"""

from . import branch
from .branch import branch_name, parse_branch
from .client import (
    DEFAULT_PORT,
    DEFAULT_RETRIES,
    DEFAULT_TIMEOUT,
    NO_READING,
    Arm,
)
from .errors import (
    ArmDidNotStart,
    ArmDidNotStop,
    ArmError,
    BadIndex,
    BadNumber,
    BeyondJointLimit,
    BranchBeyondLimits,
    Cancelled,
    ClientSilent,
    FollowingError,
    CommandRejected,
    ControllerError,
    ControllerMessage,
    ControllerTooOld,
    ControllerUnreachable,
    ControllerWarning,
    DriveFault,
    HeldAtWorkspaceEdge,
    HeldByOther,
    IkDivergence,
    JointLimitWarning,
    LinkShared,
    NotUnderstood,
    OutsideWorkspace,
    ReplyTimeout,
    SignatureMismatch,
    Stalled,
    Stopped,
    Undersized,
    ViaPointMissed,
    WaitFailed,
    WaitTimeout,
    WorkspaceLimit,
)
from .pose import Pose
from .signing import Signer
from .status import DriveState, Holder, Mode, Motion, Nearest, Status, StopCause
from .streaming import VelocityStream
from .waiting import WaitOptions

__all__ = [
    "DEFAULT_PORT",
    "DEFAULT_RETRIES",
    "DEFAULT_TIMEOUT",
    "NO_READING",
    "Arm",
    "ArmDidNotStart",
    "ArmDidNotStop",
    "ArmError",
    "BadIndex",
    "BadNumber",
    "BeyondJointLimit",
    "BranchBeyondLimits",
    "Cancelled",
    "branch",
    "branch_name",
    "parse_branch",
    "ClientSilent",
    "FollowingError",
    "CommandRejected",
    "ControllerError",
    "ControllerMessage",
    "ControllerTooOld",
    "ControllerUnreachable",
    "ControllerWarning",
    "DriveFault",
    "DriveState",
    "HeldAtWorkspaceEdge",
    "HeldByOther",
    "Holder",
    "IkDivergence",
    "JointLimitWarning",
    "LinkShared",
    "Mode",
    "Motion",
    "Nearest",
    "NotUnderstood",
    "OutsideWorkspace",
    "Pose",
    "ReplyTimeout",
    "SignatureMismatch",
    "Signer",
    "Stalled",
    "Status",
    "StopCause",
    "Stopped",
    "Undersized",
    "VelocityStream",
    "ViaPointMissed",
    "WaitFailed",
    "WaitOptions",
    "WaitTimeout",
    "WorkspaceLimit",
]
