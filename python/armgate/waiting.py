"""Waiting for the arm: polling the pose or the joints until a target is reached, and what a
wait does when it does not arrive (``ST``, and :class:`~armgate.Stopped` when the controller
stopped the motion). :class:`Waiting` is a part of :class:`~armgate.Arm`, kept apart by
concern."""

from __future__ import annotations

import contextlib
import logging
import math
import time as _time
from dataclasses import dataclass, replace
from typing import Any, Callable, Iterator, List, Optional, Sequence, Tuple, TypeVar

from .errors import (
    ArmError,
    ControllerMessage,
    ControllerTooOld,
    ReplyTimeout,
    Stalled,
    Stopped,
    WaitFailed,
    WaitTimeout,
)
from .pose import Pose
from .status import Motion

log = logging.getLogger("armgate")

T = TypeVar("T")


@dataclass(frozen=True)
class WaitOptions:
    """How a wait decides that a target is reached, and when it gives up (the Rust client's
    defaults)."""

    tolerance: float = 0.001
    """The last target is reached within this distance (m for poses, rad or m for joints)."""
    angle_tolerance: float = 0.01
    """... and, for poses, within this angle (rad)."""
    pass_tolerance: float = 0.01
    """An intermediate via point counts as passed within this distance (the arm does not dwell
    there, so a 20 Hz poll may never see it within ``tolerance``)."""
    timeout: float = 600.0
    """Give up after this many seconds (a move's wait adds its requested duration). The stall
    check ends a wait whose arm does not move; long moves must not be cut short."""
    poll: float = 0.05
    """The polling period (s)."""
    stall: Optional[float] = 3.0
    """Give up if the arm has not moved for this long (s); None: never."""
    stop: bool = True
    """When a wait ends without arriving (Ctrl-C, a timeout, a stall, no reply), send ``ST``
    so that the arm does not go on alone, and say so (the error's ``stop``). A motion the
    controller stopped is raised as :class:`~armgate.Stopped` and not stopped again."""


_STILL = 1e-6


class Waiting:
    """The waits of :class:`~armgate.Arm` (its reading and request methods do the I/O)."""

    wait_options: WaitOptions
    _has_status: Optional[bool]
    _socket: Any
    get_tcp_pose: Callable[[], Pose]
    get_joints: Callable[[], List[float]]
    get_status: Callable[..., Any]
    take_notices: Callable[[], List[ControllerMessage]]
    stop: Callable[[], None]
    watchdog: Callable[[int], None]
    _stop_report: Callable[[], Tuple[Any, Optional[int], Optional[str]]]

    def wait_for_poses(self, goals: Sequence[Pose], options: Optional[WaitOptions] = None) -> Pose:
        """Polls ``PS`` until the tool has passed ``goals`` in order (each but the last within
        ``pass_tolerance``) and reached the last one."""
        opts = options or self.wait_options

        def measure(pose: Pose, goal: Pose, last: bool) -> Tuple[float, Optional[float], bool]:
            d, a = pose.distance(goal), pose.angle_to(goal)
            if last:
                return d, a, d <= opts.tolerance and a <= opts.angle_tolerance
            return d, a, d <= opts.pass_tolerance

        def moved(a: Pose, b: Pose) -> bool:
            return a.distance(b) > _STILL or a.angle_to(b) > _STILL

        return self._owned(opts, lambda: self._wait(goals, opts, self.get_tcp_pose, measure, moved))

    def wait_for_joints(
        self, goals: Sequence[Sequence[float]], options: Optional[WaitOptions] = None
    ) -> List[float]:
        """Polls ``jP`` until the joints have passed ``goals`` in order and reached the last
        (Euclidean norm within the tolerances). A goal may give the first joints only (``KG``'s
        reply carries joints 1–6): the others are not compared."""
        opts = options or self.wait_options

        def measure(
            q: List[float], goal: List[float], last: bool
        ) -> Tuple[float, Optional[float], bool]:
            d = math.dist(q[: len(goal)], goal)
            return d, None, d <= (opts.tolerance if last else opts.pass_tolerance)

        def moved(a: List[float], b: List[float]) -> bool:
            return any(abs(x - y) > _STILL for x, y in zip(a, b))

        targets = [list(g) for g in goals]
        return self._owned(opts, lambda: self._wait(targets, opts, self.get_joints, measure, moved))

    def _owned(self, options: WaitOptions, wait: Callable[[], T]) -> T:
        """Runs a wait this client owns, with the watchdog on. If it ends without arriving, a
        stall or timeout while the controller reports a stop cause is raised as
        :class:`~armgate.Stopped` (why, and who); any other ending but a motion the controller
        ended sends ``ST`` (``options.stop``) and says so: the error's ``stop`` and message, a
        warning on the ``armgate`` logger."""
        try:
            with self._watchdog_while(options):
                return wait()
        except (Stalled, WaitTimeout) as e:
            stopped = self._explain(e)
            if stopped is not None:
                raise stopped from None
            if options.stop:
                raise e.stopped(self._stop_motion())
            raise
        except ControllerMessage as e:
            if not e.ends_motion and options.stop:
                self._say_stopped(e)
            raise
        except (ArmError, KeyboardInterrupt) as e:
            if options.stop and not isinstance(e, Stopped):
                self._say_stopped(e)
            raise

    def _explain(self, error: WaitFailed) -> Optional[Stopped]:
        """A stall or timeout that the controller caused: :class:`~armgate.Stopped` with the
        stop cause in force (a motion's start clears the last one) and who set it; asked before
        this client's own ``ST``, which would replace it. None without a cause (or an answer)."""
        try:
            cause, joint, address = self._stop_report()
        except ArmError:
            return None
        if cause is None:
            return None
        if not cause.set_by_client:
            by = "the controller"
        elif address is None:
            by = "another client"
        elif address == "{}:{}".format(*self._socket.getsockname()[:2]):
            by = "this client"
        else:
            by = f"client {address}"
        return Stopped(cause, by, joint, error.target, error.distance, error.angle)

    def _stop_motion(self) -> str:
        """Sends ``ST`` for a wait that gave up; what happened, in words."""
        try:
            self.stop()
        except ArmError as e:
            return f"ST failed ({e}): the arm may still be moving"
        return "sent ST: the arm stops and holds"

    def _say_stopped(self, error: BaseException) -> None:
        """``ST`` after ``error`` ended a wait, said on the logger and kept as ``error.stop``."""
        stop = self._stop_motion()
        log.warning("%s: %s", type(error).__name__, stop)
        try:
            error.stop = stop  # type: ignore[attr-defined]
        except AttributeError:
            pass

    @contextlib.contextmanager
    def _watchdog_while(self, options: WaitOptions) -> Iterator[None]:
        """The controller's client watchdog on (twenty polls, at least a second) for the
        block: if this program dies or loses the network while the arm moves, the controller
        stops it. A controller without one, or another client holding the arm, refuses it;
        the block runs without."""
        refused = (ControllerMessage, ControllerTooOld, ReplyTimeout)
        try:
            self.watchdog(max(1000, min(60000, round(options.poll * 20 * 1000))))
        except refused:
            yield
            return
        try:
            yield
        finally:
            try:
                self.watchdog(0)
            except refused:
                pass

    def _wait(
        self,
        goals: Sequence[T],
        options: WaitOptions,
        read: Callable[[], T],
        measure: Callable[[T, T, bool], Tuple[float, Optional[float], bool]],
        moved: Callable[[T, T], bool],
    ) -> T:
        started = _time.monotonic()
        last_move = started
        previous: Optional[T] = None
        target = 0
        while True:
            current = read()
            notices = self.take_notices()
            now = _time.monotonic()
            if previous is None or moved(previous, current):
                last_move = now
            distance: float = math.inf
            angle: Optional[float] = None
            arrived = False
            while target < len(goals):
                last = target + 1 == len(goals)
                distance, angle, reached = measure(current, goals[target], last)
                if not reached:
                    break
                if last:
                    arrived = True
                    break
                target += 1
            if arrived:
                return self._settle(current, started, options, read, moved)
            for notice in notices:
                if notice.ends_motion:
                    raise notice
            remaining = f"{distance * 1e3:.1f} mm" if angle is not None else f"{distance:.4f}"
            if options.stall is not None and now - last_move > options.stall:
                raise Stalled(
                    f"the arm stopped {remaining} from target {target + 1} "
                    f"(no motion for {options.stall} s)",
                    target,
                    distance,
                    angle,
                )
            if now - started > options.timeout:
                raise WaitTimeout(
                    f"target {target + 1} not reached within {options.timeout} s "
                    f"(still {remaining} from it)",
                    target,
                    distance,
                    angle,
                )
            previous = current
            _time.sleep(options.poll)

    def _settle(
        self,
        current: T,
        started: float,
        options: WaitOptions,
        read: Callable[[], T],
        moved: Callable[[T, T], bool],
    ) -> T:
        """After arrival within the tolerance the generator may still be finishing its profile
        (and refuses the next motion until it has): waits until the status reports no motion,
        or, from a controller without the status request, until two polls read the same."""
        while _time.monotonic() - started <= options.timeout:
            if self._has_status is not False:
                try:
                    if self.get_status(details=False).motion == Motion.IDLE:
                        return read()
                except ControllerTooOld:
                    self._has_status = False
                    continue
            else:
                _time.sleep(options.poll)
                latest = read()
                if not moved(current, latest):
                    return latest
                current = latest
                continue
            _time.sleep(options.poll)
        return current

    def _passing(self, requested: float, blend: Optional[float]) -> WaitOptions:
        # Blended via points are passed within the blend, plus the usual pass tolerance.
        options = self._options(requested)
        return replace(options, pass_tolerance=options.pass_tolerance + (blend or 0.0))

    def _options(self, requested: float, planned: float = 0.0) -> WaitOptions:
        """As the Rust tool, unless set otherwise: twice the planned duration the controller
        reported (``BG``/``jB`` reply f6, 0 for none) plus 30 s, else the default plus the
        requested duration."""
        if self.wait_options.timeout != WaitOptions.timeout:
            return self.wait_options
        if planned > 0.0:
            return replace(self.wait_options, timeout=2.0 * planned + 30.0)
        return replace(self.wait_options, timeout=WaitOptions.timeout + requested)
