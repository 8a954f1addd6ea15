"""Exceptions: one class per ``ER``/``WN`` code of docs/protocol.md and docs/drives.md, and the
client's own failures (no reply, a wait that did not arrive).

The texts are read as the Rust grammar reads them (protocol/src/client/header.rs): the table
``protocol/grammar.json``, generated from it, is what python/tests/test_grammar.py checks this
module against (every code, and a text of every form).

Every controller text becomes a :class:`ControllerMessage` subclass with the code, the whole
text and the reason after the prefix::

    try:
        arm.move_l(pose)
    except armgate.CommandRejected as e:     # ER20
        print(e.code, e.text, e.command)     # 20 'ER20 Cmd BG rejected' 'BG'
    except armgate.ControllerMessage as e:   # any other ER/WN
        ...
"""

from __future__ import annotations

import re
from typing import Any, Dict, Optional, Type


class ArmError(Exception):
    """Everything this package raises."""


class ReplyTimeout(ArmError, TimeoutError):
    """No reply arrived: every attempt (the first send and each retry) timed out."""

    def __init__(self, command: str, attempts: int, timeout: float, signed: bool = False) -> None:
        # A controller never answers a request signed with another key or for another id.
        hint = " (is the controller running, or has it another key?)" if signed else ""
        super().__init__(
            f"no reply to {command} after {attempts} attempt(s) of {timeout * 1e3:.0f} ms each"
            + hint
        )
        self.command = command
        self.attempts = attempts
        self.timeout = timeout


class SignatureMismatch(ArmError):
    """No answer signed with the key came, but other datagrams did: the controller has no key
    or another one, or someone else answers."""

    def __init__(self, command: str, count: int) -> None:
        super().__init__(
            f"no signed answer to {command}: {count} datagram(s) came unsigned or not signed "
            "with the key (has the controller this key?)"
        )
        self.command = command
        self.count = count


class ControllerUnreachable(ArmError, ConnectionError):
    """The operating system reported the controller's port as closed (ICMP port unreachable)."""


class ControllerTooOld(ArmError):
    """The controller does not know a request this client sent (it answered ``ER00``)."""


class WaitFailed(ArmError):
    """A wait for the arm ended without reaching the target.

    ``stop`` says what the client did about the motion (``"sent ST: the arm stops and holds"``,
    or why it could not), and is part of the message; None where it did nothing (the
    controller had stopped the motion already, or ``WaitOptions.stop`` is False)."""

    def __init__(self, message: str, target: int, distance: float, angle: Optional[float]):
        super().__init__(message)
        self.message = message
        self.target = target
        """The 0-based number of the target not reached."""
        self.distance = distance
        """The remaining distance (m for poses, rad or m for joints)."""
        self.angle = angle
        """For poses: the remaining angle (rad)."""
        self.stop: Optional[str] = None

    def stopped(self, stop: str) -> "WaitFailed":
        """This error, saying what was done about the motion (``stop``)."""
        self.stop = stop
        self.args = (f"{self.message}; {stop}",)
        return self

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else self.message


class Stalled(WaitFailed):
    """The arm stopped moving before it reached the target and nothing had stopped it (no
    motion-ending notice, no stop cause in ``SQ`` index 2), e.g. held at a joint limit."""


class WaitTimeout(WaitFailed, TimeoutError):
    """A wait ran out of time (and nothing had stopped the motion)."""


class Stopped(WaitFailed):
    """The controller stopped the motion being waited for: ``cause`` is its reason
    (:class:`~armgate.StopCause`, from ``SQ`` index 2), ``by`` who set it: ``"the controller"``
    (workspace, IK divergence, watchdog, ...), ``"this client"``, ``"client 127.0.0.1:40001"``
    or ``"another client"`` (one the controller does not name). ``joint`` is the 1-based joint
    of a joint-limit hold."""

    def __init__(
        self, cause: Any, by: str, joint: Optional[int], target: int, distance: float,
        angle: Optional[float],
    ) -> None:
        name = getattr(cause, "label", str(cause))
        at = f" (j{joint})" if joint else ""
        super().__init__(
            f"the motion was stopped by {by}: {name}{at} (target {target + 1} not reached)",
            target, distance, angle,
        )
        self.cause = cause
        self.by = by
        self.joint = joint


_NAMED = re.compile(r"(?:Cmd|Msg) (..)(?: |$)")
"""A command a text names: ``Cmd XX`` or ``Msg XX``, then the end or a space."""

_REFUSES = {10: "OF", 11: "ON"}
"""The refusals that name no command: of ``OF`` and of ``ON``."""


def _code(text: str) -> int:
    """The two-digit code after ``ER``/``WN``, followed by the end or a space; -1 if none."""
    code = text[2:4]
    if len(code) == 2 and code.isdigit() and text[4:5] in ("", " "):
        return int(code)
    return -1


class ControllerMessage(ArmError):
    """An ``ER``/``WN`` text from the controller.

    Raised when it answers a request (a refusal), or when it ends a motion a ``move_*`` waits
    for; otherwise handed to the ``on_notice`` callback.
    """

    code: int
    """The two-digit code (``ER20`` -> 20); -1 if the text has none."""
    text: str
    """The whole text, e.g. ``ER20 Cmd BG rejected``."""
    reason: str
    """The text after the prefix and code, e.g. ``Cmd BG rejected``."""
    command: Optional[str]
    """The request's characters that the text names (``BG``), if it names one."""

    def __init__(self, text: str) -> None:
        super().__init__(text)
        self.text = text
        self.code = _code(text)
        self.reason = text[5:] if len(text) > 4 else ""
        named = _NAMED.match(self.reason)
        self.command = named.group(1) if named else None

    @property
    def detail(self) -> str:
        """For a text that names a command, what follows it (``ER20 Cmd BG needs mode 2`` ->
        ``needs mode 2``); else the reason."""
        if self.command is None:
            return self.reason
        return self.reason[len("Cmd XX "):]

    @property
    def refuses(self) -> Optional[str]:
        """The request this text refuses, if it refuses one: the command it names, or ``OF``
        for ``ER10`` and ``ON`` for ``ER11``, which name none. Warnings refuse nothing."""
        if self.is_warning:
            return None
        return _REFUSES.get(self.code, self.command)

    @property
    def is_warning(self) -> bool:
        """``WN`` rather than ``ER``."""
        return self.text.startswith("WN")

    @property
    def ends_motion(self) -> bool:
        """Whether a running motion will not complete: ``ER21`` (workspace limit), ``WN22`` (IK
        divergence), ``WN27`` (via point missed), ``ER41`` (the client watchdog stopped the arm),
        ``ER43`` (a following error stopped it) and drive faults ``ER30``..``ER39``."""
        if self.is_warning:
            return self.code in (22, 27)
        return self.code in (21, 41, 43) or 30 <= self.code <= 39

    @classmethod
    def from_text(cls, text: str) -> "ControllerMessage":
        """The exception of the class for this text's prefix and code."""
        number = _code(text)
        kind = _WARNINGS if text.startswith("WN") else _ERRORS
        if text.startswith("ER") and 30 <= number <= 39:
            return DriveFault(text)
        return kind.get(number, ControllerWarning if kind is _WARNINGS else ControllerError)(text)


class ControllerError(ControllerMessage):
    """An ``ER`` text."""


class ControllerWarning(ControllerMessage):
    """A ``WN`` text."""


class NotUnderstood(ControllerError):
    """``ER00 Cmd XX not understood``: unknown command characters."""


class Undersized(ControllerError):
    """``ER01 Msg XX undersized.``: a datagram shorter than 30 bytes."""


class ArmDidNotStop(ControllerError):
    """``ER10 Arm ...``: the answer to ``OF`` when the drives could not be stopped (``ER10 Arm
    did not stop``; newer controllers say why: ``ER10 Arm already off``)."""


class ArmDidNotStart(ControllerError):
    """``ER11 Arm ...``: the answer to ``ON`` when the drives could not be started (``ER11 Arm
    did not start``; newer controllers say why: ``ER11 Arm already on``)."""


class CommandRejected(ControllerError):
    """``ER20 Cmd XX ...``: wrong mode, a motion is running, no goal, not ready (``rejected``;
    newer controllers give the reason: ``ER20 Cmd BG needs mode 2``, see :attr:`detail`)."""


class WorkspaceLimit(ControllerError):
    """``ER21 Work space limit.``: a set-point or the arm left the workspace (ends a motion)."""


class BadNumber(ControllerError):
    """``ER23 Cmd XX bad number``: NaN/Inf, a zero quaternion, an invalid mode."""


class BadIndex(ControllerError):
    """``ER24 Cmd XX bad index``: via slot >= 20, or joint bank misuse."""


class OutsideWorkspace(ControllerError):
    """``ER25 Cmd XX outside workspace``: a goal or via point outside the bounds or in a box."""


class BeyondJointLimit(ControllerError):
    """``ER26 Cmd XX beyond joint limit``: a joint goal, via point or recalibration outside the
    joint limits."""


class DriveFault(ControllerError):
    """``ER30``..``ER39``: a drive fault (docs/drives.md), e.g. ``ER33 J4 PT buffer underflow``."""

    @property
    def joint(self) -> Optional[int]:
        """The joint (from 1) the fault names, if it names one."""
        named = re.match(r"J(\d+) ", self.reason)
        return int(named.group(1)) if named else None


class HeldByOther(ControllerError):
    """``ER40 Cmd XX by 192.168.1.2``: another client controls the arm while it moves
    (``by another client`` for an IPv6 one). Raised by :meth:`~armgate.Arm.request` with
    ``holder``, its address and port (``"192.168.1.2:40001"``, from ``SQ`` 3), in the message
    with what to do."""

    holder: Optional[str] = None

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else self.text


class ClientSilent(ControllerError):
    """``ER41 client silent 500 ms``: this client said nothing for longer than its watchdog
    (``WD``) while the arm moved, and the arm was stopped (ends a motion)."""


class Cancelled(ControllerError):
    """``ER42 Cmd XX cancelled by ST``: a planning request that waited for a later control tick
    was cancelled by a stop that came after it."""


class FollowingError(ControllerError):
    """``ER43 j3 following error 0.123``: joint 3's measured position was this far from its
    command, more than the robot file's ``max_following_error``: the arm was stopped (ends a
    motion)."""


class JointLimitWarning(ControllerWarning):
    """``WN12 Joint limit.``: a joint set-point was clamped (the motion goes on); ``WN12 j6 at
    limit 2.967``: a velocity stream holds joint 6 before its limit."""


class HeldAtWorkspaceEdge(ControllerWarning):
    """``WN13 Held at workspace edge.``: a velocity stream holds the tool at the workspace's
    edge or before an exclusion box; ``WN13 Held: L6 hits B1``: it holds the arm before link 6
    would touch box 1 (``L5 hits L2``: link 2; ``L6 out``: the bounds), after slowing as the
    gap shrank (:meth:`~armgate.Arm.get_nearest` tells the gap)."""


class LinkShared(ControllerWarning):
    """``WN14 link 7 shared``: signed requests from two clients interleave on one link id (the
    older timestamps of each are dropped); give each client its own link id."""


class IkDivergence(ControllerWarning):
    """``WN22 Inv Kin Divergence.``: the IK could not track the set-point; the arm holds."""


class BranchBeyondLimits(ControllerError):
    """``ER44 Cmd KG branch past limits``: the pose has IK solutions within the joint limits,
    none in the configuration (``branch``) asked for; ``ik_solutions`` lists those it has."""


class ViaPointMissed(ControllerWarning):
    """``WN27 Via point missed.``: a sequence stopped."""


_ERRORS: Dict[int, Type[ControllerMessage]] = {
    0: NotUnderstood,
    1: Undersized,
    10: ArmDidNotStop,
    11: ArmDidNotStart,
    20: CommandRejected,
    21: WorkspaceLimit,
    23: BadNumber,
    24: BadIndex,
    25: OutsideWorkspace,
    26: BeyondJointLimit,
    40: HeldByOther,
    41: ClientSilent,
    42: Cancelled,
    43: FollowingError,
    44: BranchBeyondLimits,
}

_WARNINGS: Dict[int, Type[ControllerMessage]] = {
    12: JointLimitWarning,
    13: HeldAtWorkspaceEdge,
    14: LinkShared,
    22: IkDivergence,
    27: ViaPointMissed,
}
