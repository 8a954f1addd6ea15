"""Tool poses as the protocol carries them: position (m) and a quaternion (x, y, z, w)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence, Tuple, Union


@dataclass(frozen=True)
class Pose:
    """A tool pose: position in metres and orientation as a unit quaternion, scalar last."""

    x: float
    y: float
    z: float
    qx: float = 0.0
    qy: float = 0.0
    qz: float = 0.0
    qw: float = 1.0

    @classmethod
    def from_rpy(
        cls, x: float, y: float, z: float, roll: float, pitch: float, yaw: float
    ) -> "Pose":
        """A pose from a position and roll, pitch, yaw (rad; ``R = Rz(yaw) Ry(pitch) Rx(roll)``,
        as the controller's ``GT`` and ``VP`` take them)."""
        cr, sr = math.cos(roll / 2), math.sin(roll / 2)
        cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
        cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
        qw = cr * cp * cy + sr * sp * sy
        qx = sr * cp * cy - cr * sp * sy
        qy = cr * sp * cy + sr * cp * sy
        qz = cr * cp * sy - sr * sp * cy
        if qw < 0:
            qx, qy, qz, qw = -qx, -qy, -qz, -qw
        return cls(x, y, z, qx, qy, qz, qw)

    @property
    def xyz(self) -> Tuple[float, float, float]:
        """The position (m)."""
        return (self.x, self.y, self.z)

    @property
    def quaternion(self) -> Tuple[float, float, float, float]:
        """The orientation (x, y, z, w)."""
        return (self.qx, self.qy, self.qz, self.qw)

    def _unit(self) -> Tuple[float, float, float, float]:
        n = math.sqrt(sum(c * c for c in self.quaternion))
        if n == 0 or not math.isfinite(n):
            return (0.0, 0.0, 0.0, 1.0)
        return (self.qx / n, self.qy / n, self.qz / n, self.qw / n)

    def rotation(self) -> Tuple[Tuple[float, float, float], ...]:
        """The orientation as a 3x3 rotation matrix (rows); a zero quaternion is the identity."""
        x, y, z, w = self._unit()
        return (
            (1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)),
            (2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)),
            (2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)),
        )

    @property
    def rpy(self) -> Tuple[float, float, float]:
        """Roll, pitch, yaw (rad), extracted as the controller does (spec section 2.4), including
        its gimbal branch: if ``|r20| > 1 - 1e-6`` then yaw = 0."""
        (r00, r01, _), (r10, r11, _), (r20, r21, r22) = self.rotation()
        if abs(r20) > 1 - 1e-6:
            sign = -1.0 if r20 < 0 else 1.0
            return (-sign * math.atan2(r01, r11), -sign * math.pi / 2, 0.0)
        return (
            math.atan2(r21, r22),
            math.atan2(-r20, math.sqrt(r00 * r00 + r10 * r10)),
            math.atan2(r10, r00),
        )

    def distance(self, other: "Pose") -> float:
        """The distance between the positions (m)."""
        return math.dist(self.xyz, other.xyz)

    def angle_to(self, other: "Pose") -> float:
        """The angle of the rotation between the orientations (rad, in [0, pi])."""
        dot = abs(sum(a * b for a, b in zip(self._unit(), other._unit())))
        return 2 * math.acos(min(dot, 1.0))


PoseLike = Union[Pose, Sequence[float]]
"""A :class:`Pose`, or six numbers x, y, z (m), roll, pitch, yaw (rad)."""


def as_pose(pose: PoseLike) -> Pose:
    """``pose`` as a :class:`Pose`."""
    if isinstance(pose, Pose):
        return pose
    values = [float(v) for v in pose]
    if len(values) != 6:
        raise ValueError(
            f"{len(values)} numbers: a pose is a Pose or x, y, z, roll, pitch, yaw"
        )
    return Pose.from_rpy(*values)
