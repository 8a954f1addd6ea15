#!/usr/bin/env python3
"""Cross-checks armgate's body distances (core/src/geometry: segment-segment and segment-box,
capsules) against an independent library: Coal (PyPI `coal`, the successor of FCL/hpp-fcl).

For each robot (default: every file in robots/):

1. `core/examples/body_capsules.rs` places the robot's capsules at N random poses (uniform within
   the joint limits, by the chain's frames as the control tick places them) and prints them with
   the robot file's boxes plus one random box per pose, and armgate's gap (surface distance, <= 0
   when touching or overlapping) for every pair of capsules and every capsule-box pair.
2. The same capsules (coal.Capsule: radius and length, along z, placed at the midpoint) and boxes
   (coal.Box) are built in Coal, which computes each distance (coal.distance) and whether they
   collide (coal.collide).
3. Where both are apart (gap > 0), |armgate - coal| <= TOLERANCE (1e-6 m) for every pair (so
   also for each pose's minimum distance); and every pair Coal calls colliding armgate calls touching (gap <= 1e-9): a
   pair armgate calls clear that Coal calls colliding is a failure, the other way round is
   counted (Coal's collision tolerance).

Needs numpy and coal from PyPI, cargo for the example:
    python3 -m venv target/body-crosscheck && target/body-crosscheck/bin/pip install coal numpy
    target/body-crosscheck/bin/python tools/body_crosscheck.py [--poses 10000] [ROBOT ...]
Exits 1 on any failure, 0 otherwise.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import coal
import numpy as np

REPO = Path(__file__).resolve().parents[1]
TOLERANCE = 1e-6
TOUCHING = 1e-9


def example() -> Path:
    """Builds (if needed) and returns the body_capsules example, release."""
    env = dict(os.environ, CARGO_INCREMENTAL="0")
    out = subprocess.run(
        ["cargo", "build", "--release", "-p", "armgate-core", "--example", "body_capsules",
         "--message-format=json-render-diagnostics"],
        cwd=REPO, env=env, check=True, capture_output=True, text=True,
    ).stdout
    for line in out.splitlines():
        message = json.loads(line)
        if message.get("executable") and message["target"]["name"] == "body_capsules":
            return Path(message["executable"])
    sys.exit("body_crosscheck: the example was not built")


def capsule(a: np.ndarray, b: np.ndarray, radius: float):
    """A Coal capsule from `a` to `b` and its placement."""
    axis = b - a
    length = float(np.linalg.norm(axis))
    rotation = np.eye(3)
    if length > 0.0:
        z = axis / length
        helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        x = np.cross(helper, z)
        x /= np.linalg.norm(x)
        rotation = np.column_stack([x, np.cross(z, x), z])
    return coal.Capsule(radius, length), coal.Transform3s(rotation, (a + b) / 2.0)


def box(bounds: list[float]):
    """A Coal box from `[x_min, x_max, y_min, y_max, z_min, z_max]` and its placement."""
    lo, hi = np.array(bounds[0::2]), np.array(bounds[1::2])
    return coal.Box(*(hi - lo)), coal.Transform3s(np.eye(3), (lo + hi) / 2.0)


def coal_distance(one, two) -> tuple[float, bool]:
    """Coal's distance of two placed shapes, and whether it calls them colliding."""
    request = coal.DistanceRequest()
    request.gjk_tolerance = 1e-12
    request.abs_err = 0.0
    request.rel_err = 0.0
    result = coal.DistanceResult()
    distance = coal.distance(one[0], one[1], two[0], two[1], request, result)
    hit_request, hit_result = coal.CollisionRequest(), coal.CollisionResult()
    colliding = coal.collide(one[0], one[1], two[0], two[1], hit_request, hit_result) > 0
    return distance, colliding


def check_robot(binary: Path, robot: str, poses: int) -> dict:
    out = subprocess.run(
        [str(binary), str(REPO / "robots" / f"{robot}.toml"), str(poses)],
        check=True, capture_output=True, text=True,
    ).stdout
    worst, compared, failures, coal_only, armgate_only = 0.0, 0, [], 0, 0
    for index, line in enumerate(out.splitlines()):
        pose = json.loads(line)
        shapes = [capsule(np.array(c[1:4]), np.array(c[4:7]), c[7]) for c in pose["capsules"]]
        boxes = [box(b) for b in pose["boxes"]]
        items = [(shapes[i], shapes[j], gap, f"capsules {i} {j}") for i, j, gap in pose["pairs"]]
        items += [(shapes[i], boxes[k], gap, f"capsule {i} box {k}") for i, k, gap in pose["box_gaps"]]
        for one, two, gap, what in items:
            distance, colliding = coal_distance(one, two)
            if colliding and gap > TOUCHING:
                failures.append(f"pose {index} {what}: Coal collides, armgate gap {gap:.3e}")
            elif gap <= TOUCHING and not colliding:
                armgate_only += 1
            if colliding:
                coal_only += gap > TOUCHING
                continue
            if gap > 0.0 and distance > 0.0:
                compared += 1
                diff = abs(gap - distance)
                worst = max(worst, diff)
                if diff > TOLERANCE:
                    failures.append(f"pose {index} {what}: armgate {gap:.9f} coal {distance:.9f}")
    return {
        "robot": robot, "poses": poses, "distances compared": compared,
        "largest difference (m)": worst,
        "touching by armgate only": armgate_only, "failures": failures,
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--poses", type=int, default=10_000)
    parser.add_argument("robots", nargs="*")
    args = parser.parse_args()
    robots = args.robots or sorted(p.stem for p in (REPO / "robots").glob("*.toml"))
    binary = example()
    failed = False
    for robot in robots:
        report = check_robot(binary, robot, args.poses)
        print(
            f"{robot:20} {report['poses']} poses, {report['distances compared']} distances: "
            f"largest |armgate - coal| {report['largest difference (m)']:.2e} m, "
            f"touching by armgate only {report['touching by armgate only']}, "
            f"failures {len(report['failures'])}"
        )
        for failure in report["failures"][:10]:
            print("   ", failure)
        failed |= bool(report["failures"])
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
