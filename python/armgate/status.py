"""The controller's mode and its status report (``SQ`` -> ``QS``)."""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Optional, Sequence, Union


class Mode(enum.IntEnum):
    """The command mode (``CM``)."""

    OFF = 0
    """No generator drives the arm."""
    JOINT = 1
    """Joint moves and joint sequences (``jB``, ``jE``)."""
    CARTESIAN = 2
    """Cartesian moves and sequences (``BG``, ``VE``)."""

    @classmethod
    def parse(cls, mode: Union["Mode", int, str]) -> "Mode":
        """A mode from a :class:`Mode`, its number or its name (``"cartesian"``, ``"cart"``)."""
        if isinstance(mode, str):
            names = {"off": cls.OFF, "joint": cls.JOINT, "cartesian": cls.CARTESIAN}
            names["cart"] = cls.CARTESIAN
            try:
                return names[mode.lower()]
            except KeyError:
                raise ValueError(f"mode {mode!r}: expected off, joint or cartesian") from None
        return cls(mode)


class DriveState(enum.IntEnum):
    """The drives' state (status field f1)."""

    OFF = 0
    STARTING = 1
    RUNNING = 2
    STOPPING = 3
    FAULTED = 4


class Motion(enum.IntEnum):
    """What the arm is doing (status field f4)."""

    IDLE = 0
    JOINT_MOVE = 1
    CARTESIAN_MOVE = 2
    JOINT_SEQUENCE = 3
    CARTESIAN_SEQUENCE = 4
    STREAMING = 5
    STOPPING = 6
    """Coming to rest after a stop; :meth:`~armgate.Client.get_stop_cause` says why."""


class StopCause(enum.IntEnum):
    """Why the arm last stopped or is held (``SQ`` index 2, f0; 0 is none)."""

    STOP = 1
    """``ST`` or ``jR``."""
    MODE_CHANGE = 2
    POWER_OFF = 3
    WORKSPACE = 4
    IK_DIVERGENCE = 5
    STREAM_TIMEOUT = 6
    JOINT_LIMIT = 7
    """A stream holds a joint at its limit (the joint is reported with it)."""
    CLIENT_SILENT = 8
    """The controlling client was silent for longer than its watchdog (``WD``)."""
    FOLLOWING_ERROR = 9
    """A joint's measured position was further from its command than the robot file's
    ``max_following_error`` (``ER43``; the joint is reported with it)."""

    @property
    def label(self) -> str:
        """As the Rust client names it: ``ST``, ``workspace limit``, ``client silent``."""
        return _CAUSE_LABELS[self]

    @property
    def set_by_client(self) -> bool:
        """Whether a client's request sets this cause (``ST``/``jR``, ``CM``, ``OF``); the
        others are the controller's own."""
        return self in (StopCause.STOP, StopCause.MODE_CHANGE, StopCause.POWER_OFF)


_CAUSE_LABELS = {
    StopCause.STOP: "ST",
    StopCause.MODE_CHANGE: "mode change",
    StopCause.POWER_OFF: "OF",
    StopCause.WORKSPACE: "workspace limit",
    StopCause.IK_DIVERGENCE: "IK divergence",
    StopCause.STREAM_TIMEOUT: "stream timeout",
    StopCause.JOINT_LIMIT: "joint limit",
    StopCause.CLIENT_SILENT: "client silent",
}


class Holder(enum.IntEnum):
    """Who holds the arm, as ``SQ`` index 3 tells the asking client."""

    NOBODY = 0
    YOU = 1
    OTHER = 2


def address_of(high: float, low: float, port: float) -> Optional[str]:
    """``"a.b.c.d:port"`` from an IPv4 address in two 16-bit halves and a port (``SQ`` 2 and
    3), None for 0 (none, or an IPv6 client)."""
    ip = (int(round(high)) << 16) | int(round(low))
    if ip == 0:
        return None
    return f"{ip >> 24}.{(ip >> 16) & 255}.{(ip >> 8) & 255}.{ip & 255}:{int(round(port))}"


def _enum(kind, value: float):  # type: ignore[no-untyped-def]
    """The member of ``kind`` for ``value``, or the rounded number if it is not one."""
    number = int(round(value))
    try:
        return kind(number)
    except ValueError:
        return number


@dataclass(frozen=True)
class Status:
    """The controller's status report."""

    mode: Mode
    drive_state: DriveState
    drive_fault: int
    """The code NN of the drive fault ``ER3N`` in force, 0 for none."""
    joint_count: int
    motion: Motion
    refusals: int
    """How many requests were refused since the controller started."""
    uptime: float
    """Seconds since the controller started."""
    name: str
    """The robot's name from its robot file."""
    stop_cause: Optional[StopCause] = None
    """Why the arm last stopped or is held (``SQ`` 2); None for none, or an older controller."""
    stopped_by: Optional[str] = None
    """The address of the client whose request set :attr:`stop_cause` (``ST``, ``CM``, ``OF``)."""
    holder: Optional[Holder] = None
    """Who holds the arm (``SQ`` 3); None from an older controller."""
    holder_address: Optional[str] = None
    """The holder's address and port, ``"127.0.0.1:40001"`` (None: nobody, or IPv6)."""
    watchdog_ms: Optional[int] = None
    """The client watchdog (ms, 0 off)."""
    clients: Optional[int] = None
    """The clients the controller knows."""

    @classmethod
    def from_replies(cls, values: Sequence[float], name: bytes) -> "Status":
        """The status from the index-0 reply's values and the index-1 reply's bytes 2..30."""
        f = list(values)
        return cls(
            mode=_enum(Mode, f[0]),
            drive_state=_enum(DriveState, f[1]),
            drive_fault=int(round(f[2])),
            joint_count=int(round(f[3])),
            motion=_enum(Motion, f[4]),
            refusals=int(round(f[5])),
            uptime=float(f[6]),
            name=name.split(b"\0", 1)[0].decode("ascii", "replace"),
        )


OBSTACLE_KINDS = [(0, "box", "B"), (1, "link", "L"), (2, "bounds", "out")]
"""``SQ`` index 7's f2: the kind of obstacle, its name and the short form the texts use
(``L6 hits B1``, ``L5 hits L2``, ``L6 out``); ``protocol/grammar.json`` lists the same
(``obstacles``, checked by ``test_grammar.py``)."""


@dataclass(frozen=True)
class Nearest:
    """The smallest gap between the arm's body and what it is kept from, at the measured pose,
    and the pair (``SQ`` index 7)."""

    gap: float
    """The gap (m) between the capsules' surfaces, or to a box or the bounds' faces; 0 or
    less: touching or overlapping."""
    link: int
    """The link (0 the base; the last carries the tool)."""
    obstacle: str
    """``"box"``, ``"link"`` (another link of the arm) or ``"bounds"`` (the workspace's)."""
    number: int
    """The box's number (from 1, in the robot file's order) or the other link's; 0 for the
    bounds."""
    margin: float
    """The robot file's ``collision.margin`` (m)."""

    @property
    def pair(self) -> str:
        """The pair as the texts name it: ``"L6 B1"``, ``"L5 L2"``, ``"L6 out"``."""
        short = next(s for _, name, s in OBSTACLE_KINDS if name == self.obstacle)
        return f"L{self.link} {short}" if self.obstacle == "bounds" else f"L{self.link} {short}{self.number}"

    @classmethod
    def from_values(cls, values: Sequence[float]) -> Optional["Nearest"]:
        """The report from the index-7 reply's values; None when there is nothing to measure
        (f1 = -1: no body, or no measurement yet)."""
        f = list(values)
        if f[1] < 0:
            return None
        kind = int(round(f[2]))
        names = {k: name for k, name, _ in OBSTACLE_KINDS}
        if kind not in names:
            raise ValueError(f"SQ 7: obstacle kind {f[2]} is none of {sorted(names)}")
        return cls(
            gap=float(f[0]),
            link=int(round(f[1])),
            obstacle=names[kind],
            number=int(round(f[3])),
            margin=float(f[4]),
        )
