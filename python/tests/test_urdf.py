"""``armgate urdf`` checked by an independent URDF parser (yourdfpy, from PyPI): for every
shipped robot file and a calibrated one (Hayati beta, [base], a full tool), the frame of every
link in the URDF equals armgate's forward kinematics to 1e-9 m / 1e-9 rad at 1,000 random
joint vectors within the limits; and every link carries the body's capsules (core's collision
model) as collision geometry, a cylinder and two spheres each, which yourdfpy's FK places where
armgate's control tick places the capsules.

Skipped without yourdfpy, unless ``ARMGATE_REQUIRE_VIZ=1`` (CI sets it): then it fails.
"""

from __future__ import annotations

import csv
import json
import math
import subprocess
from pathlib import Path
from typing import List

import pytest

from conftest import REPO, require_viz_package, viz_binary

ROBOTS: List[Path] = sorted((REPO / "robots").glob("*.toml")) + [
    REPO / "python" / "tests" / "data" / "ur5-calibrated.toml"
]
SAMPLES = 1000


@pytest.fixture(scope="module")
def yourdfpy():
    return require_viz_package("yourdfpy")


def rotation_angle(a, b) -> float:
    """The angle of the rotation between two 3x3 rotation matrices (accurate near zero)."""
    r = [[sum(a[k][i] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    skew = (r[2][1] - r[1][2], r[0][2] - r[2][0], r[1][0] - r[0][1])
    s = 0.5 * math.sqrt(sum(v * v for v in skew))
    c = 0.5 * (r[0][0] + r[1][1] + r[2][2] - 1.0)
    return math.atan2(s, c)


@pytest.mark.parametrize("robot", ROBOTS, ids=lambda p: p.stem)
def test_urdf_frames_are_armgates_fk(robot: Path, yourdfpy, tmp_path: Path) -> None:
    urdf_path = tmp_path / "robot.urdf"
    fk_path = tmp_path / "fk.csv"
    subprocess.run(
        [str(viz_binary()), "urdf", str(robot), "--out", str(urdf_path),
         "--fk-csv", str(fk_path), "--samples", str(SAMPLES)],
        check=True,
    )
    model = yourdfpy.URDF.load(str(urdf_path), build_collision_scene_graph=False,
                               load_meshes=False, load_collision_meshes=False)
    joints = [name for name in model.actuated_joint_names]
    with fk_path.open() as f:
        rows = list(csv.reader(f))
    header, rows = rows[0], rows[1:]
    n = sum(1 for h in header if h.startswith("q"))
    assert joints == [f"joint_{k}" for k in range(1, n + 1)]
    links = [f"link_{k}" for k in range(1, n + 1)] + ["tool"]
    assert len(rows) == SAMPLES
    worst_position = worst_angle = 0.0
    for row in rows:
        values = [float(v) for v in row]
        model.update_cfg(values[:n])
        for k, link in enumerate(links):
            expected = values[n + 16 * k: n + 16 * (k + 1)]
            got = model.get_transform(frame_to=link, frame_from="world")
            e = [expected[4 * i: 4 * i + 4] for i in range(4)]
            position = math.dist([got[i][3] for i in range(3)], [e[i][3] for i in range(3)])
            angle = rotation_angle([list(got[i][:3]) for i in range(3)],
                                   [e[i][:3] for i in range(3)])
            worst_position = max(worst_position, position)
            worst_angle = max(worst_angle, angle)
    print(f"{robot.stem}: worst {worst_position:.2e} m, {worst_angle:.2e} rad")
    assert worst_position < 1e-9
    assert worst_angle < 1e-9


def test_exclusion_boxes_are_fixed_links(yourdfpy, tmp_path: Path) -> None:
    robot = REPO / "python" / "tests" / "data" / "ur5-calibrated.toml"
    out = subprocess.run([str(viz_binary()), "urdf", str(robot)], check=True,
                         capture_output=True, text=True).stdout
    path = tmp_path / "r.urdf"
    path.write_text(out)
    model = yourdfpy.URDF.load(str(path), load_meshes=False)
    box = model.link_map["exclusion_box_1"]
    assert list(box.visuals[0].geometry.box.size) == pytest.approx([0.4, 0.4, 0.3])
    centre = model.get_transform(frame_to="exclusion_box_1", frame_from="world")
    assert [centre[i][3] for i in range(3)] == pytest.approx([0.3, -0.2, 0.65])
    assert model.joint_map["joint_1"].limit.velocity == pytest.approx(math.pi)


def transform_point(m, p) -> list:
    return [sum(m[i][k] * p[k] for k in range(3)) + m[i][3] for i in range(3)]


@pytest.mark.parametrize("robot", ROBOTS, ids=lambda p: p.stem)
def test_collision_geometry_is_armgates_body(robot: Path, yourdfpy, tmp_path: Path) -> None:
    """Every capsule of the body (``--body-json``: core's capsules placed by the chain at 20
    seeded random poses) is in the URDF on its link, as ``capsule_K`` (a cylinder of the
    capsule's radius, left out for a sphere) and ``capsule_K_a``/``_b`` (spheres at the ends);
    yourdfpy's FK puts the spheres' centres on armgate's ends and the cylinder's axis between
    them, to 1e-9 m."""
    urdf_path = tmp_path / "robot.urdf"
    body_path = tmp_path / "body.json"
    subprocess.run(
        [str(viz_binary()), "urdf", str(robot), "--out", str(urdf_path),
         "--body-json", str(body_path), "--samples", "20"],
        check=True,
    )
    model = yourdfpy.URDF.load(str(urdf_path), build_collision_scene_graph=False,
                               load_meshes=False, load_collision_meshes=False)
    body = json.loads(body_path.read_text())
    capsules, poses = body["capsules"], body["poses"]
    assert capsules and len(poses) == 20
    # Every link that moves and the base carry collision geometry; only the body's.
    links_with_capsules = {c["urdf_link"] for c in capsules}
    n = len(model.actuated_joint_names)
    assert {"base_link"} | {f"link_{k}" for k in range(1, n + 1)} >= links_with_capsules
    assert f"link_{n}" in links_with_capsules  # the tool's capsule
    shapes = {}
    for name, link in model.link_map.items():
        for c in link.collisions:
            shapes[c.name] = (name, c)
    expected_names = set()
    for k, c in enumerate(capsules, start=1):
        for suffix in ("_a", "_b"):
            link, shape = shapes[f"capsule_{k}{suffix}"]
            assert link == c["urdf_link"]
            assert shape.geometry.sphere.radius == pytest.approx(c["radius"], abs=1e-12)
            expected_names.add(f"capsule_{k}{suffix}")
        if f"capsule_{k}" in shapes:
            link, shape = shapes[f"capsule_{k}"]
            assert link == c["urdf_link"]
            assert shape.geometry.cylinder.radius == pytest.approx(c["radius"], abs=1e-12)
            expected_names.add(f"capsule_{k}")
    assert set(shapes) == expected_names
    worst = 0.0
    for pose in poses:
        model.update_cfg(pose["q"])
        for k, (c, (a, b)) in enumerate(zip(capsules, pose["ends"]), start=1):
            link = model.get_transform(frame_to=c["urdf_link"], frame_from="world")
            centre = lambda name: transform_point(  # noqa: E731
                link, [shapes[name][1].origin[i][3] for i in range(3)])
            worst = max(worst, math.dist(centre(f"capsule_{k}_a"), a),
                        math.dist(centre(f"capsule_{k}_b"), b))
            if f"capsule_{k}" in shapes:
                cylinder = shapes[f"capsule_{k}"][1]
                assert cylinder.geometry.cylinder.length == pytest.approx(math.dist(a, b), abs=1e-9)
                mid = [(a[i] + b[i]) / 2 for i in range(3)]
                worst = max(worst, math.dist(centre(f"capsule_{k}"), mid))
                # The cylinder's z axis runs along the capsule's axis.
                o = cylinder.origin
                axis = [sum(link[i][j] * o[j][2] for j in range(3)) for i in range(3)]
                half = [(b[i] - a[i]) / math.dist(a, b) for i in range(3)]
                assert sum(x * y for x, y in zip(axis, half)) == pytest.approx(1.0, abs=1e-9)
            else:
                assert math.dist(a, b) < 1e-6
    print(f"{robot.stem}: {len(capsules)} capsules, worst {worst:.2e} m")
    assert worst < 1e-9
