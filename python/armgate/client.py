"""The :class:`Arm`: one controller, one request at a time, with timeouts and retries."""

from __future__ import annotations

import collections
import logging
import math
import socket
import time as _time
from dataclasses import replace
from typing import (
    Callable,
    Deque,
    List,
    Optional,
    Sequence,
    Tuple,
    TypeVar,
    Union,
)

from . import wire
from .branch import PRESENT_INDEX, parse_branch
from .signing import IDENTITY_INDEX, RESERVE_SECONDS, KeyLike, Signer
from .streaming import Streaming
from .errors import (
    ArmError,
    BadIndex,
    ControllerMessage,
    ControllerTooOld,
    ControllerUnreachable,
    HeldByOther,
    NotUnderstood,
    ReplyTimeout,
    SignatureMismatch,
)
from .pose import Pose, PoseLike, as_pose
from .status import Holder, Mode, Nearest, Status, StopCause, address_of
from .waiting import Waiting, WaitOptions

DEFAULT_PORT = 7031
"""The controller's UDP port (``armgate-sim`` listens on 127.0.0.1:7031)."""
DEFAULT_TIMEOUT = 0.2
"""Seconds to wait for the reply after each send."""
DEFAULT_RETRIES = 3
"""How many times a request is re-sent after a send timed out (at most 1 + 3 sends)."""
NOTICE_CAPACITY = 64
"""Unsolicited notices kept until :meth:`Arm.take_notices` (the oldest is dropped first)."""
NO_READING = -100.0
"""The temperature a drive that has not been heard from reports (read as None)."""

WRITE_JOINTS = 6
"""Joints per write request (``jG``, ``jV``, ``RC``)."""
READ_JOINTS = 7
"""Joints per read reply (``jP``, ``TM``)."""
MAX_JOINTS = 8

log = logging.getLogger("armgate")

T = TypeVar("T")
NoticeCallback = Callable[[ControllerMessage], None]




def _split_host_port(host: str, port: int) -> Tuple[str, int]:
    """``"host:port"`` or ``"[v6]:port"`` given as ``host`` while ``port`` is the default."""
    name, colon, number = host.rpartition(":")
    if port != DEFAULT_PORT or not colon or not number.isdigit():
        return host, port
    if name.startswith("[") and name.endswith("]"):
        return name[1:-1], int(number)
    if ":" in name:  # a bare IPv6 address: its last group is not a port
        return host, port
    return name, int(number)


class Arm(Waiting, Streaming):
    """A client of one armgate controller.

    ``Arm("127.0.0.1", port=7031)`` opens a UDP socket; nothing is sent until a request. Every
    request waits ``timeout`` seconds for its reply and is re-sent up to ``retries`` times. A
    refusal (``ER`` text naming the request) raises its :class:`~armgate.ControllerMessage`
    subclass at once, without retrying. Unsolicited ``ER``/``WN`` texts that arrive meanwhile go
    to ``on_notice`` (default: logged on the ``armgate`` logger) and are kept for
    :meth:`take_notices`.

    ``joints``: the arm's joint count; by default it is asked of the controller (``SQ``) or, on
    a controller without the status request, read off the ``TM`` reply.

    ``host`` may also be ``"host:port"`` (as the Rust client's ``--addr``) when ``port`` is left
    at its default. An address that does not resolve raises :class:`ValueError`.

    ``key``: sign every request and accept only answers signed with this key (32 bytes, a string
    of 64 hex digits, or the path of a key file: 64 hex digits on one line, readable by its
    owner only); with a key an unanswered request is re-sent for at least 2 s
    (:data:`~armgate.signing.RESERVE_AHEAD`) whatever ``timeout`` and ``retries``, as long as a
    controller that has just restarted drops signed requests; on link ``link_id`` (1..255; clients that run at the same time need their
    own; default: a free one the controller sets aside, :attr:`link_id`), for the controller
    ``controller_id`` (default: the id the controller names in its first signed answer,
    :attr:`controller_id`). See docs/safety.md, "Signing".
    """

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = DEFAULT_PORT,
        *,
        timeout: float = DEFAULT_TIMEOUT,
        retries: int = DEFAULT_RETRIES,
        joints: Optional[int] = None,
        on_notice: Optional[NoticeCallback] = None,
        wait_options: WaitOptions = WaitOptions(),
        key: Optional[KeyLike] = None,
        link_id: Optional[int] = None,
        controller_id: Optional[int] = None,
    ) -> None:
        self._signer = Signer(key, link_id, controller_id) if key is not None else None
        self._signed_at = 0
        self.unverified = 0
        """Datagrams dropped because they were not signed with the key, or were old."""
        host, port = _split_host_port(host, port)
        try:
            info = socket.getaddrinfo(host, port, type=socket.SOCK_DGRAM)[0]
        except socket.gaierror as e:
            raise ValueError(
                f"cannot resolve the controller address {host!r} port {port}: {e.strerror}"
                f" (expected Arm('127.0.0.1', port=7031) or Arm('127.0.0.1:7031'))"
            ) from e
        self._socket = socket.socket(info[0], socket.SOCK_DGRAM)
        # A connected socket receives only the controller's datagrams.
        self._socket.connect(info[4])
        self.timeout = timeout
        self.retries = retries
        self.wait_options = wait_options
        self.on_notice = on_notice
        self._joints = joints
        self._has_status: Optional[bool] = None
        if joints is not None:
            _check_count(joints)
        self._notices: Deque[ControllerMessage] = collections.deque(maxlen=NOTICE_CAPACITY)
        self.stale_replies = 0
        """Normal replies that answered no outstanding request (late answers to retries)."""

    # -- connection ------------------------------------------------------------------------

    def close(self) -> None:
        """Closes the socket."""
        self._socket.close()

    def __enter__(self) -> "Arm":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- reading ---------------------------------------------------------------------------

    def get_tcp_pose(self) -> Pose:
        """``PS``: the measured tool pose (position in m, quaternion x, y, z, w; ``.rpy`` gives
        roll, pitch, yaw)."""
        return Pose(*self.request("PS").values)

    def get_joints(self) -> List[float]:
        """``jP``: the measured joints (rad, or m for prismatic joints); for more than seven
        joints a second ``jP`` with index 0x80 reads joints 7.. (bank 2)."""
        return self._read_banks("jP", self.joint_count)

    def get_temperatures(self) -> List[Optional[float]]:
        """``TM``: the drive temperatures (deg C), None for a drive not heard from yet."""
        return [None if t == NO_READING else t for t in self._read_banks("TM", self.joint_count)]

    def get_status(self, details: bool = True) -> Status:
        """``SQ``: mode, drive state and fault, joint count, motion, refusals, uptime, name;
        with ``details`` also the stop cause in force and who set it (``SQ`` 2), who holds the
        arm (address and port), the watchdog and the clients known (``SQ`` 3), where the
        controller reports them.

        Raises :class:`~armgate.ControllerTooOld` if the controller does not know ``SQ``."""
        try:
            numbers = self.request("SQ", index=0)
            named = self._exchange("SQ", wire.encode("SQ", (), 1), 1)
        except NotUnderstood as e:
            raise ControllerTooOld(
                f"the controller does not know the status request SQ ({e.text}); update it"
            ) from e
        status = Status.from_replies(numbers.values, named[2:30])
        if not details:
            return status
        cause, _, by = self._stop_report()
        status = replace(status, stop_cause=cause, stopped_by=by)
        try:
            session = self.request("SQ", index=3).values
        except (BadIndex, NotUnderstood):
            return status
        holder = int(round(session[0]))
        return replace(
            status,
            holder=Holder(holder) if holder in Holder._value2member_map_ else None,
            holder_address=address_of(session[1], session[2], session[3]),
            watchdog_ms=int(round(session[4])),
            clients=int(round(session[6])),
        )

    def get_stop_cause(self) -> Tuple[Optional[StopCause], Optional[int]]:
        """``SQ`` index 2: why the arm last stopped or is held, and the joint (1-based) of a
        joint-limit hold or a following error; ``(None, None)`` for none (or from a controller without index 2)."""
        cause, joint, _ = self._stop_report()
        return cause, joint

    def get_nearest(self) -> Optional[Nearest]:
        """``SQ`` index 7: the smallest gap between the arm's body (its links' capsules) and the
        exclusion boxes, the workspace bounds and its other links at the measured pose, with
        the pair; None when there is nothing to measure, or from a controller without it."""
        try:
            values = self.request("SQ", index=7).values
        except (BadIndex, NotUnderstood):
            return None
        return Nearest.from_values(values)

    def _stop_report(self) -> Tuple[Optional[StopCause], Optional[int], Optional[str]]:
        """``SQ`` index 2: the cause, the joint (1-based) and the address of the client that
        set a client's cause; all None from a controller without index 2."""
        try:
            values = self.request("SQ", index=2).values
        except (BadIndex, NotUnderstood):
            return (None, None, None)
        cause = int(round(values[0]))
        joint = int(round(values[1]))
        return (
            StopCause(cause) if cause in StopCause._value2member_map_ else None,
            joint or None,
            address_of(values[2], values[3], values[4]),
        )

    @property
    def joint_count(self) -> int:
        """The arm's joint count (asked once, see the class description)."""
        if self._joints is None:
            try:
                self._joints = self.get_status(details=False).joint_count
            except ControllerTooOld:
                self._has_status = False
                self._joints = self._count_from_temperatures()
            _check_count(self._joints)
        return self._joints

    def _count_from_temperatures(self) -> int:
        # TM answers joints 1..7 and fills the rest with -1000.
        values = self.request("TM").values
        count = sum(1 for v in values if v != -1000.0)
        if count == READ_JOINTS and self.request("TM", index=wire.BANK2).values[1] != -1000.0:
            count = MAX_JOINTS
        return count

    # -- commanding ------------------------------------------------------------------------

    def set_mode(self, mode: Union[Mode, int, str]) -> Mode:
        """``CM``: the command mode (``Mode.CARTESIAN``, ``1``, ``"joint"``); returns the mode
        the controller reports."""
        value = Mode.parse(mode) if not isinstance(mode, int) else mode
        reply = self.request("CM", (float(value),))
        return Mode(int(round(reply.values[0])))

    def on(self) -> None:
        """``ON``: starts the drives; clears a drive fault (``ArmDidNotStart`` if refused)."""
        self.request("ON")

    def off(self) -> None:
        """``OF``: stops the drives (``ArmDidNotStop`` if refused)."""
        self.request("OF")

    def stop(self) -> None:
        """``ST``: stops every motion and sequence; the arm holds its commanded position."""
        self.request("ST")

    def watchdog(self, ms: int) -> None:
        """``WD``: the client watchdog: while the arm moves and this client (holding the arm)
        is silent for longer than ``ms``, the controller stops it (``ER41``); 0 turns it off."""
        self.request("WD", [float(ms)])

    def twist(
        self,
        linear: Sequence[float],
        angular: Sequence[float] = (0.0, 0.0, 0.0),
        tool_frame: bool = False,
    ) -> float:
        """``TW``: streams a tool twist (Cartesian mode): ``linear`` (m/s) and ``angular``
        (rad/s), in the base frame or the tool frame. It holds for three control periods, the
        time returned (s): send the next one before then, or the arm ramps to rest.

        After a stop (``ST`` from any client, ``OF``, ``ER21``, ``WN22``, ``ER41``, ``ER43``, or
        this stream's own timeout) the stream is latched: a twist other than zero is refused
        (``ER20 Cmd TW after ST: send 0``, ``after idle: send 0``) until a zero twist re-arms
        it, sent on purpose when a stream starts: :meth:`velocity_stream` does so."""
        values = [float(v) for v in linear] + [float(v) for v in angular]
        if len(values) != 6:
            raise ValueError("a twist has three linear and three angular components")
        index = wire.TOOL_FRAME if tool_frame else 0
        return float(self.request("TW", values, index).values[6])

    def joint_velocity(self, rates: Sequence[float]) -> float:
        """``jW``: streams joint rates (rad/s, joint mode), one per joint (bank 2 first for
        more than six). Returns how long they hold (s), as :meth:`twist`."""
        reply = self._write_banks("jW", self._check_joints(rates), 0, 0.0)
        return float(reply.values[6])

    def recalibrate(self, q: Sequence[float], wait: bool = True) -> None:
        """``RC``: the arm's current position becomes the joint angles ``q`` (mode off only).

        The controller measures the joints a cycle or two later; with ``wait`` this returns once
        ``get_joints()`` reads ``q``, so that the next request starts from there."""
        q = self._check_joints(q)
        self._write_banks("RC", q, 0, 0.0)
        if wait:
            self.wait_for_joints([q], replace(self.wait_options, timeout=2.0, stall=None))

    def move_l(
        self, pose: PoseLike, time: Optional[float] = None, wait: bool = True
    ) -> Optional[Pose]:
        """A Cartesian move of the tool to ``pose`` (a :class:`Pose`, or x, y, z, roll, pitch,
        yaw) in Cartesian mode.

        With ``time`` (s) the move takes at least that long (``GT``), else as short as the
        limits allow (``GL``); then ``BG``. With ``wait`` the tool pose is polled until it is
        reached and the motion has ended (the pose is returned), and a notice that ends the
        motion (``ER21``, ``WN22``, ``ER3x``) is raised."""
        goal = as_pose(pose)
        if time is None:
            self.request("GL", goal.xyz + goal.quaternion)
        else:
            self.request("GT", goal.xyz + goal.rpy + (float(time),))
        planned = self.request("BG").values[6]
        if not wait:
            return None
        return self.wait_for_poses([goal], self._options(time or 0.0, planned))

    def move_j(
        self, q: Sequence[float], time: Optional[float] = None, wait: bool = True
    ) -> Optional[List[float]]:
        """A joint move to ``q`` in joint mode: ``jG`` + ``jB``, or with ``time`` (s) a one-point
        joint sequence (``jC``, ``jV``, ``jE``) that takes at least that long. With ``wait`` the
        joints are polled until they are reached and the motion has ended (returned)."""
        q = self._check_joints(q)
        if time is None:
            self._write_banks("jG", q, 0, 0.0)
            planned = self.request("jB").values[6]
        else:
            planned = 0.0
            self.request("jC")
            self._write_banks("jV", q, 0, float(time))
            self.request("jE")
        if not wait:
            return None
        return self.wait_for_joints([q], self._options(time or 0.0, planned))

    def choose_redundancy(
        self, theta3: Optional[float] = None, theta5: Optional[float] = None
    ) -> None:
        """``KR``: the values of the redundancy parameters of a 7–8 joint arm (θ3, and θ5 on
        eight; None: the present value) for this client's next ``KG`` and its ``KS`` reads
        that ask for them (:meth:`move_j_to_pose`, :meth:`ik_solutions` send it themselves).
        Refused (``ER24``, :class:`~armgate.BadIndex`) on an arm without them, ``ER26`` beyond
        a joint's limits."""
        index = (wire.THETA3 if theta3 is not None else 0) | (
            wire.THETA5 if theta5 is not None else 0
        )
        values = [float(theta3 or 0.0), float(theta5 or 0.0)]
        self.request("KR", values, index)

    def _chosen(self, theta3: Optional[float], theta5: Optional[float]) -> int:
        """``KR`` if a value is given, and the index bit of the ``KG``/``KS`` that uses it."""
        if theta3 is None and theta5 is None:
            return 0
        self.choose_redundancy(theta3, theta5)
        return wire.CHOSEN

    def ik_solutions(
        self,
        pose: PoseLike,
        theta3: Optional[float] = None,
        theta5: Optional[float] = None,
    ) -> Optional[List[Tuple[int, List[float]]]]:
        """Every closed-form IK solution of ``pose`` within the joint limits (``KS``), as
        (branch bits, joints) pairs; branch bit 1 shoulder right, 2 elbow down, 4 wrist flip
        (``armgate.branch.branch_name`` names them). None if the robot
        has no closed form (docs/kinematics.md). On an arm of more than six joints a second
        ``KS`` with index bit 7 reads each solution's joints 7.. (bank 2); its solutions are
        those for the present values of the redundancy parameters (θ3, and θ5 on eight), or
        for ``theta3`` (``theta5``) where given (sent first with ``KR``)."""
        goal = as_pose(pose)
        values = goal.xyz + goal.rpy
        chosen = self._chosen(theta3, theta5)
        first = self.request("KS", values, chosen)
        count = int(first.values[6])
        if count < 0:
            return None
        joints = self.joint_count
        solutions = []
        for k in range(count):
            reply = first if k == 0 else self.request("KS", values, k | chosen)
            q = list(reply.values[:6])
            if joints > 6:
                upper = self.request("KS", values, k | wire.BANK2 | chosen)
                q += list(upper.values[: joints - 6])
            solutions.append((reply.index, q))
        return solutions

    def get_configuration(self) -> Optional[int]:
        """The configuration branch of the present joints (``SQ`` index 5; bits as
        :meth:`ik_solutions` gives them), None on a robot without a closed form."""
        value = self.request("SQ", index=PRESENT_INDEX).values[0]
        return None if value < 0 else int(value)

    def move_j_to_pose(
        self,
        pose: PoseLike,
        branch: Optional[Union[int, str]] = None,
        time: Optional[float] = None,
        wait: bool = True,
        theta3: Optional[float] = None,
        theta5: Optional[float] = None,
    ) -> Tuple[List[float], int]:
        """A joint move (joint mode) to the IK solution of ``pose`` on configuration ``branch``
        (``"shoulder-left,elbow-up,wrist-noflip"``, ``"lun"`` or its number: bits 1 shoulder
        right, 2 elbow down, 4 wrist flip; ``BranchBeyondLimits`` if it has no solution within
        the joint limits, ValueError for no branch), or without one the solution nearest the present
        joints (``KG``); on a 7–8 joint arm with the present θ3 (θ5), or ``theta3``
        (``theta5``) where given (sent first with ``KR``; no solution for them: refused, no
        other values are tried). Returns the goal's joints 1–6 and the branch taken (8: none,
        a robot without a closed form); with ``wait`` the joints are polled until reached."""
        goal = as_pose(pose)
        bits = 8 if branch is None else parse_branch(branch)
        chosen = self._chosen(theta3, theta5)
        index = bits | chosen
        reply = self.request("KG", goal.xyz + goal.rpy + (float(time or 0.0),), index)
        q = list(reply.values[:6])
        if wait:
            self.wait_for_joints([q], self._options(time or 0.0))
        return q, reply.index

    def set_via_tolerance(self, cartesian: bool, slot: int, tolerance: Optional[float]) -> float:
        """``VT`` (Cartesian slots, m + rad) or ``jT`` (joint slots, rad): the blend tolerance of
        via point ``slot`` (0..19). The sequence passes that point within it without stopping;
        0 stops there; None gives the slot back the robot file's default. Returns the tolerance
        now in effect for the slot. ``VC``/``jC`` reset every slot to the default."""
        if tolerance is not None and not (math.isfinite(tolerance) and tolerance >= 0.0):
            raise ValueError(f"blend tolerance {tolerance} must be a finite number >= 0")
        value = -1.0 if tolerance is None else float(tolerance)
        reply = self.request("VT" if cartesian else "jT", [value], index=slot)
        return float(reply.values[0])

    def run_via(
        self,
        points: Sequence[Tuple[Union[Pose, Sequence[float]], float]],
        wait: bool = True,
        blend: Optional[float] = None,
    ) -> Union[Pose, List[float], None]:
        """Runs via points ``[(target, time), ...]``: each target a :class:`Pose` (a Cartesian
        sequence, in Cartesian mode: ``VC``, ``VP`` per point, ``VE``) or a list of joint values
        (a joint sequence, in joint mode: ``jC``, ``jV``, ``jE``), reached no faster than its
        ``time`` (s). At most 20 points. With ``blend`` (m + rad, or rad for joints) every point
        gets that blend tolerance (``VT``/``jT``): the arm passes through within it without
        stopping. With ``wait`` the arm is polled until it has passed every point, reached the
        last and the sequence has ended (returned)."""
        if not points:
            raise ValueError("no via points")
        cartesian = isinstance(points[0][0], Pose)
        if any(isinstance(target, Pose) != cartesian for target, _ in points):
            raise ValueError("via points are all poses or all joint vectors")
        total = sum(float(t) for _, t in points)
        if cartesian:
            goals = [as_pose(target) for target, _ in points]
            self.request("VC")
            for slot, (goal, (_, t)) in enumerate(zip(goals, points)):
                self.request("VP", goal.xyz + goal.rpy + (float(t),), index=slot)
                if blend is not None:
                    self.set_via_tolerance(True, slot, blend)
            self.request("VE")
            return self.wait_for_poses(goals, self._passing(total, blend)) if wait else None
        qs = [self._check_joints(target) for target, _ in points]  # type: ignore[arg-type]
        self.request("jC")
        for slot, (q, (_, t)) in enumerate(zip(qs, points)):
            self._write_banks("jV", q, slot, float(t))
            if blend is not None:
                self.set_via_tolerance(False, slot, blend)
        self.request("jE")
        return self.wait_for_joints(qs, self._passing(total, blend)) if wait else None

    # -- notices ---------------------------------------------------------------------------

    def take_notices(self) -> List[ControllerMessage]:
        """Removes and returns the unsolicited notices received so far, oldest first (reading
        whatever is waiting on the socket first)."""
        self._drain()
        notices = list(self._notices)
        self._notices.clear()
        return notices

    def _notice(self, text: str) -> None:
        notice = ControllerMessage.from_text(text)
        self._notices.append(notice)
        if self.on_notice is not None:
            self.on_notice(notice)
        else:
            log.warning("controller: %s", text)

    def _drain(self) -> None:
        self._socket.setblocking(False)
        try:
            while True:
                try:
                    datagram = self._socket.recv(2 * wire.MESSAGE_LEN)
                except (BlockingIOError, InterruptedError):
                    return
                except (ConnectionRefusedError, ConnectionResetError):
                    # An ICMP error left over from an earlier send.
                    continue
                verified = self._verified(datagram)
                if verified is None:
                    continue
                text = wire.text_of(verified)
                if text is not None:
                    self._notice(text)
                else:
                    self.stale_replies += 1
        finally:
            self._socket.setblocking(True)

    # -- requests --------------------------------------------------------------------------

    def request(self, chars: str, values: Sequence[float] = (), index: int = 0) -> wire.Message:
        """Sends any request and returns its reply; raises the typed exception of an ``ER``
        text that answers it, :class:`~armgate.ReplyTimeout` if every attempt timed out. A
        :class:`~armgate.HeldByOther` (``ER40``, whose text has no room for a port) names the
        holder with its port (``SQ`` 3) and says what to do."""
        try:
            datagram = self._exchange(chars, wire.encode(chars, values, index), index)
        except HeldByOther as e:
            raise self._with_holder(e) from None
        message = wire.decode(datagram)
        assert message is not None  # _exchange returns only 31-byte replies
        return message

    def _with_holder(self, error: HeldByOther) -> HeldByOther:
        """``error`` with the holder's address and port from ``SQ`` 3, where it answers."""
        try:
            session = self.request("SQ", index=3).values
        except ArmError:
            return error
        holder = address_of(session[1], session[2], session[3])
        error.holder = holder
        if holder is not None:
            error.args = (
                f"{error.text} ({holder} holds the arm while it moves: wait until its motion "
                "ends, or stop() it, which any client may; then the next request takes "
                "control)",
            )
        return error

    @property
    def controller_id(self) -> Optional[int]:
        """The id of the controller the signed requests are for (None without a key); asked of
        the controller (``SQ`` index 6) if not given."""
        if self._signer is None:
            return None
        if self._signer.controller_id is None:
            self.identify()
        return self._signer.controller_id

    @property
    def link_id(self) -> Optional[int]:
        """The link id the signed requests go on (None without a key); a free one set aside by
        the controller if not given."""
        if self._signer is None:
            return None
        if self._signer.needs_identity:
            self.identify()
        return self._signer.link_id

    def identify(self) -> int:
        """The controller's id, from its identity report (``SQ`` index 6); a signer that did
        not know it signs for it from now on, on the link the controller set aside for it
        unless one was given."""
        reply = self.request("SQ", index=IDENTITY_INDEX)
        high, low = int(reply.values[0]), int(reply.values[1])
        controller = high << 16 | low
        if self._signer is not None:
            self._signer.identified(controller, int(reply.values[4]))
        return controller

    def _exchange(self, chars: str, datagram: bytes, index: int) -> bytes:
        if (
            self._signer is not None
            and self._signer.needs_identity
            and not (chars == "SQ" and index == IDENTITY_INDEX)
        ):
            self.identify()
        # Whatever arrived before this request cannot be its reply.
        self._drain()
        attempts = self.retries + 1
        # A controller that has just restarted drops signed requests other than stops for up
        # to RESERVE_AHEAD (docs/safety.md): with a key, resends go on for at least that long,
        # as the Rust client's do.
        window = RESERVE_SECONDS if self._signer is not None else 0.0
        extra = math.ceil(window / max(self.timeout, 1e-6))
        started = _time.monotonic()
        refused = False
        unverified = self.unverified
        sent = 0
        # When the last send left: the resends end only after one sent `window` after the first.
        last_sent = 0.0
        for attempt in range(attempts + extra + 1):
            answered = self.unverified > unverified
            if attempt >= attempts and (refused or answered or last_sent >= window):
                break
            sent += 1
            last_sent = _time.monotonic() - started
            outgoing = datagram
            if self._signer is not None:
                # Each attempt signed anew: the controller serves a timestamp once.
                outgoing, timestamp = self._signer.sign(datagram)
                if attempt == 0:
                    self._signed_at = timestamp
            try:
                self._socket.send(outgoing)
            except (ConnectionRefusedError, ConnectionResetError):
                refused = True
                continue
            outcome = self._await_reply(chars, index)
            if isinstance(outcome, bytes):
                return outcome
            refused = outcome == "refused"
        if refused:
            raise ControllerUnreachable(
                f"nothing listens at {self._socket.getpeername()} (connection refused); "
                "is the controller running?"
            )
        if self.unverified > unverified:
            raise SignatureMismatch(chars, self.unverified - unverified)
        raise ReplyTimeout(chars, sent, self.timeout, signed=self._signer is not None)

    def _verified(self, datagram: bytes) -> Optional[bytes]:
        """The datagram as it is without a key; with one, its message if signed with the key
        and not older than the last request (else None, counted)."""
        if self._signer is None:
            return datagram
        message = self._signer.open(datagram, self._signed_at)
        if message is None:
            self.unverified += 1
        return message

    def _await_reply(self, chars: str, index: int) -> Union[bytes, str]:
        deadline = _time.monotonic() + self.timeout
        while True:
            left = deadline - _time.monotonic()
            if left <= 0:
                return "timeout"
            self._socket.settimeout(left)
            try:
                datagram = self._socket.recv(2 * wire.MESSAGE_LEN)
            except socket.timeout:
                return "timeout"
            except (ConnectionRefusedError, ConnectionResetError):
                return "refused"
            except InterruptedError:
                continue
            finally:
                self._socket.settimeout(None)
            verified = self._verified(datagram)
            if verified is None:
                continue
            datagram = verified
            kind, text = wire.classify(chars, index, datagram)
            if kind == wire.REPLY:
                return datagram[: wire.MESSAGE_LEN]
            if kind == wire.REJECTED:
                assert text is not None
                raise ControllerMessage.from_text(text)
            if kind == wire.NOTICE:
                assert text is not None
                self._notice(text)
            else:
                self.stale_replies += 1

    # -- joint banks -----------------------------------------------------------------------

    def _check_joints(self, q: Sequence[float]) -> List[float]:
        values = [float(v) for v in q]
        if len(values) != self.joint_count:
            raise ValueError(f"{len(values)} joint values, but the arm has {self.joint_count}")
        return values

    def _read_banks(self, chars: str, n: int) -> List[float]:
        """Joints 1..7 from the bank-1 reply, joints 8.. from the bank-2 reply (which starts at
        joint 7)."""
        values = list(self.request(chars).values)
        if n > READ_JOINTS:
            upper = self.request(chars, index=wire.BANK2).values
            values += upper[READ_JOINTS - WRITE_JOINTS :]
        return values[:n]

    def _write_banks(self, chars: str, q: Sequence[float], slot: int, f6: float) -> wire.Message:
        """Writes a joint vector: for more than six joints bank 2 (joints 7.., index bit 7)
        first, then bank 1 (joints 1..6), which completes the vector (docs/protocol.md).
        Returns the bank-1 reply."""
        _check_count(len(q))
        if not 0 <= slot < wire.BANK2:
            raise ValueError(f"via slot {slot}: slots are 0..127 (bit 7 selects the bank)")

        def bank(joints: Sequence[float]) -> List[float]:
            return list(joints) + [0.0] * (WRITE_JOINTS - len(joints)) + [f6]

        if len(q) > WRITE_JOINTS:
            self.request(chars, bank(q[WRITE_JOINTS:]), slot | wire.BANK2)
        return self.request(chars, bank(q[:WRITE_JOINTS]), slot)


def _check_count(n: int) -> None:
    if not 1 <= n <= MAX_JOINTS:
        raise ValueError(f"{n} joints: an arm has 1 to {MAX_JOINTS} joints")
