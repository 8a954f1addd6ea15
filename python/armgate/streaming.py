"""Velocity streams started and ended on purpose (``TW``, ``jW``).

Every stop latches, a stream's own timeout included (docs/safety.md): after ``ST`` from any
client, ``OF``, ``ER21``, ``WN22``, ``ER41``, ``ER43`` or a stream that went quiet for longer
than its hold time (a network stall), a twist or joint rates other than zero are refused
(``ER20 Cmd TW after ST: send 0``, ``after idle: send 0``) until a zero command re-arms the
stream. :class:`VelocityStream` sends that zero once when its stream starts and once more when
it ends on purpose (so that its end is no timeout); a stream that a refusal or another error
ended sends nothing more by itself, so that it never re-arms after a stop it did not ask for::

    with arm.velocity_stream() as stream:
        while jogging():
            time.sleep(stream.twist([0.0, 0.0, 0.01]) / 3)

:class:`Streaming` is a part of :class:`~armgate.Arm`, kept apart by concern.
"""

from __future__ import annotations

from types import TracebackType
from typing import Any, Callable, Optional, Sequence, Type

from .errors import ArmError


class VelocityStream:
    """One stream: its first command is preceded by the same kind of command at rest (which
    re-arms the stream after a stop), and leaving the ``with`` block normally or by
    ``KeyboardInterrupt`` sends it once more. After an :class:`~armgate.ArmError` from any
    of its commands (a refusal such as ``after ST: send 0``, no reply) it sends nothing more
    by itself; its later commands go out as they are and are refused while the stop holds."""

    def __init__(self, arm: Any) -> None:
        self._arm = arm
        self._at_rest: Optional[Callable[[], float]] = None
        self._failed = False

    def __enter__(self) -> "VelocityStream":
        return self

    def __exit__(
        self,
        kind: Optional[Type[BaseException]],
        error: Optional[BaseException],
        traceback: Optional[TracebackType],
    ) -> None:
        on_purpose = kind is None or issubclass(kind, KeyboardInterrupt)
        if self._at_rest is not None and on_purpose and not self._failed:
            self._at_rest()

    def twist(
        self,
        linear: Sequence[float],
        angular: Sequence[float] = (0.0, 0.0, 0.0),
        tool_frame: bool = False,
    ) -> float:
        """:meth:`Arm.twist <armgate.Arm.twist>` within the stream; returns the hold time (s)."""
        return self._send(
            lambda: self._arm.twist(linear, angular, tool_frame),
            lambda: self._arm.twist((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), tool_frame),
        )

    def joint_velocity(self, rates: Sequence[float]) -> float:
        """:meth:`Arm.joint_velocity <armgate.Arm.joint_velocity>` within the stream."""
        zeros = [0.0] * len(rates)
        return self._send(
            lambda: self._arm.joint_velocity(rates),
            lambda: self._arm.joint_velocity(zeros),
        )

    def _send(self, command: Callable[[], float], at_rest: Callable[[], float]) -> float:
        try:
            if self._at_rest is None:
                self._at_rest = at_rest
                at_rest()
            self._at_rest = at_rest
            return command()
        except ArmError:
            self._failed = True
            raise


class Streaming:
    """Velocity streams of :class:`~armgate.Arm`."""

    def velocity_stream(self) -> VelocityStream:
        """A stream started and ended on purpose (:class:`VelocityStream`), for ``with``."""
        return VelocityStream(self)
