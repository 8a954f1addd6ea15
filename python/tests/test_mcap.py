"""``armgate-sim --mcap``: a 20 s run read back by an independent reader (the ``mcap`` package
from PyPI): every channel with its schema, the expected message counts, joint states at the
tick rate, monotonic log times (the simulation's), the URDF as attachment and channel; the
body's capsules in the scene (those of the URDF's collision geometry) with the nearest pair
coloured, its gap checked against the scene's own geometry.

Skipped without the ``mcap`` package, unless ``ARMGATE_REQUIRE_VIZ=1`` (CI sets it).
"""

from __future__ import annotations

import base64
import json
import math
import signal
import xml.etree.ElementTree as ElementTree
import subprocess
import time
from collections import Counter, defaultdict
from pathlib import Path

import pytest

import armgate
from conftest import REPO, Sim, require_viz_package, viz_binary

CHANNELS = {
    "/robot_description": "foxglove.RobotDescription",
    "/joint_states": "foxglove.JointStates",
    "/joint_command": "foxglove.JointStates",
    "/tf": "foxglove.FrameTransforms",
    "/tool_pose": "foxglove.PoseInFrame",
    "/setpoint": "foxglove.PoseInFrame",
    "/goal": "foxglove.PoseInFrame",
    "/planned_path": "foxglove.PosesInFrame",
    "/workspace": "foxglove.SceneUpdate",
    "/body": "foxglove.SceneUpdate",
    "/clearance": "armgate.Clearance",
    "/log": "foxglove.Log",
    "/udp": "armgate.Datagram",
    "/can": "armgate.CanFrame",
}
PERIOD_NS = 19_440_000  # ranger-mk1's control period
RUN_S = 20.0


@pytest.fixture(scope="module")
def mcap_reader():
    return require_viz_package("mcap.reader").make_reader


@pytest.fixture(scope="module")
def recording(mcap_reader, tmp_path_factory: pytest.TempPathFactory) -> dict:
    """20 s of ranger-mk1: a Cartesian move (stopped), a joint move, a refused request, pose polls;
    then SIGTERM (the file must be complete all the same)."""
    path = tmp_path_factory.mktemp("mcap") / "run.mcap"
    started = time.monotonic()
    sim = Sim("ranger-mk1", ["--mcap", str(path)])
    sent = 0
    with armgate.Arm("127.0.0.1", port=sim.port, retries=0, timeout=1.0) as arm:
        def request(chars: str, values=(), index: int = 0):
            nonlocal sent
            sent += 1
            try:
                return arm.request(chars, values, index)
            except armgate.ControllerMessage:
                return None

        request("CM", [2])
        request("GT", [0.0, 0.3, 0.8, 0.0, 1.5708, 0.0, 3.0])
        request("BG")
        request("XY")  # unknown: an ER00 reply
        time.sleep(4.0)
        # The move (30 s at ranger-mk1's speed limits) is stopped; the supervisor brings the
        # arm to rest along the path (SQ f4 = 0: holding), at most 8 s.
        request("ST")
        deadline = time.monotonic() + 8.0
        while time.monotonic() < deadline:
            time.sleep(0.25)
            status = request("SQ")
            if status is not None and status.values[4] == 0:
                break
        request("CM", [1])
        request("jG", [1.5708, 0.1, 1.5, 0.0, 1.2, 0.0])
        request("jB")
        while time.monotonic() - started < RUN_S:
            request("PS")
            time.sleep(0.5)
    sim.process.send_signal(signal.SIGTERM)
    _, stderr = sim.process.communicate(timeout=20)
    with path.open("rb") as f:
        reader = mcap_reader(f)
        summary = reader.get_summary()
        messages = [(channel.topic, message) for _, channel, message in reader.iter_messages(log_time_order=False)]
        attachments = list(reader.iter_attachments())
        metadata = list(reader.iter_metadata())
    return {"summary": summary, "messages": messages, "attachments": attachments,
            "metadata": metadata, "sent": sent, "port": sim.port, "stderr": stderr.decode(),
            "path": path}


def payloads(recording: dict, topic: str) -> list:
    return [json.loads(m.data) for t, m in recording["messages"] if t == topic]


def test_every_channel_has_its_schema(recording: dict) -> None:
    summary = recording["summary"]
    found = {c.topic: summary.schemas[c.schema_id] for c in summary.channels.values()}
    assert {topic: schema.name for topic, schema in found.items()} == CHANNELS
    for channel in summary.channels.values():
        assert channel.message_encoding == "json"
        schema = summary.schemas[channel.schema_id]
        assert schema.encoding == "jsonschema"
        assert json.loads(schema.data)["title"] == schema.name
    assert "0 events dropped" in recording["stderr"], recording["stderr"]


def test_joint_states_come_at_the_tick_rate(recording: dict) -> None:
    times = [m.log_time for t, m in recording["messages"] if t == "/joint_states"]
    # The run is ~20 s from the first tick; the start-up and SIGTERM take a little of it.
    assert RUN_S * 0.85 < len(times) * PERIOD_NS * 1e-9 < RUN_S * 1.15, len(times)
    steps = Counter(b - a for a, b in zip(times, times[1:]))
    # One per tick on the schedule: every step a whole number of periods (a tick the shell
    # skipped, more than 50 periods late on a loaded machine, leaves a gap), nearly all one.
    assert all(step > 0 and step % PERIOD_NS == 0 for step in steps), steps.most_common(3)
    assert steps[PERIOD_NS] >= 0.99 * (len(times) - 1), steps.most_common(3)
    joints = payloads(recording, "/joint_states")[0]["joints"]
    assert [j["name"] for j in joints] == [f"joint_{k}" for k in range(1, 7)]
    counts = Counter(t for t, _ in recording["messages"])
    assert counts["/tf"] == counts["/tool_pose"] == counts["/joint_states"] == counts["/clearance"]
    assert 0 < counts["/joint_command"] <= counts["/joint_states"]
    assert counts["/can"] > counts["/joint_states"]  # set-points and answers every tick


def test_log_times_are_monotonic(recording: dict) -> None:
    times = [m.log_time for _, m in recording["messages"]]
    assert all(a <= b for a, b in zip(times, times[1:]))
    per_topic = defaultdict(list)
    for topic, m in recording["messages"]:
        per_topic[topic].append(m.log_time)
        assert m.publish_time == m.log_time
    assert per_topic["/robot_description"] == [0]


def test_every_request_reply_and_notice_is_logged(recording: dict) -> None:
    udp = payloads(recording, "/udp")
    log = payloads(recording, "/log")
    assert len(log) == len(udp)
    to_sim = [d for d in udp if d["to"].endswith(f":{recording['port']}")]
    from_test = Counter(d["from"] for d in to_sim).most_common()
    # The readiness probe used other sockets; the test client sent `sent` requests.
    assert recording["sent"] in [n for _, n in from_test]
    messages = [entry["message"] for entry in log]
    assert any(m.startswith("TG 0 0.3 0.8 0 1.5708 0 3 ") for m in messages), messages[:10]
    errors = [entry for entry in log if entry["level"] == 4]
    assert any(e["message"].startswith("ER00") for e in errors)


def test_goals_and_planned_paths(recording: dict) -> None:
    goals = payloads(recording, "/goal")
    paths = payloads(recording, "/planned_path")
    assert len(goals) == len(paths) == 2
    cartesian = goals[0]["pose"]["position"]
    assert [cartesian["x"], cartesian["y"], cartesian["z"]] == pytest.approx([0.0, 0.3, 0.8], abs=1e-6)
    for goal, path in zip(goals, paths):
        assert path["poses"][-1]["position"] == pytest.approx(goal["pose"]["position"], abs=1e-6)
        assert goal["frame_id"] == path["frame_id"] == "world"


def test_workspace_and_urdf_are_in_the_file(recording: dict) -> None:
    urdf = subprocess.run([str(viz_binary()), "urdf", str(REPO / "robots" / "ranger-mk1.toml")],
                          check=True, capture_output=True).stdout
    assert [a.name for a in recording["attachments"]] == ["robot.urdf"]
    assert recording["attachments"][0].data == urdf
    description = payloads(recording, "/robot_description")
    assert len(description) == 1 and description[0]["format"] == "urdf"
    assert base64.b64decode(description[0]["data"]) == urdf
    scene = payloads(recording, "/workspace")
    assert len(scene) == 1
    cubes = scene[0]["entities"][1]["cubes"]
    # ranger-mk1's base column, z from -0.1 to 0.35 m (5.2 cm under the stowed arm, issue 35).
    assert len(cubes) == 1 and cubes[0]["size"] == pytest.approx({"x": 0.4, "y": 0.4, "z": 0.45})
    assert recording["metadata"][0].metadata["robot"] == "ranger-mk1"


def test_the_clearance_plot_of_the_run(recording: dict, tmp_path: Path) -> None:
    """``armgate-viz clearance`` turns the run's /clearance into an SVG: the least gap to the
    boxes, inside the bounds and between links over the run's time, the margin, and the
    refused request (ER00) as a marker."""
    out = tmp_path / "clearance.svg"
    printed = subprocess.run([str(viz_binary()), "clearance", str(recording["path"]), "--out", str(out)],
                             check=True, capture_output=True, text=True).stdout
    assert printed.strip() == str(out)
    svg = out.read_text()
    root = ElementTree.fromstring(svg)
    texts = [t.text.strip() for t in root.iter("{http://www.w3.org/2000/svg}text") if t.text]
    for text in ("minimum distance at the measured joints", "t (s)", "distance (m)", "to the boxes",
                 "inside the bounds", "between links", "margin", "ER00"):
        assert text in texts or any(text in t for t in texts), (text, texts)
    lines = [p for p in root.iter("{http://www.w3.org/2000/svg}polyline")
             if len(p.get("points").split()) >= 50]
    assert len(lines) >= 3, [len(p.get("points").split()) for p in root.iter("{http://www.w3.org/2000/svg}polyline")]
    # The time axis spans the run: its last tick label is near the run's length.
    ticks = [float(t) for t in texts if t.replace(".", "", 1).isdigit()]
    assert RUN_S * 0.7 < max(ticks) < RUN_S * 1.3 + 5, ticks


def test_record_reads_a_controller_over_the_protocol(mcap_reader, sim_factory, tmp_path: Path) -> None:
    """``armgate-viz record`` (what ``armgate record`` runs) against armgate-sim: jP and PS at
    the stated rate, SQ once a second; the tool pose PS reports is the FK of the joints jP
    reports (to the wire's float precision)."""
    sim = sim_factory("ranger-mk1")
    path = tmp_path / "record.mcap"
    result = subprocess.run(
        [str(viz_binary()), "record", str(path), "--robot", str(sim.robot),
         "--addr", f"127.0.0.1:{sim.port}", "--rate", "20", "--duration", "3"],
        check=True, capture_output=True, text=True,
    )
    assert "0 without reply" in result.stderr, result.stderr
    with path.open("rb") as f:
        reader = mcap_reader(f)
        summary = reader.get_summary()
        counts = {summary.channels[k].topic: v
                  for k, v in summary.statistics.channel_message_counts.items()}
        messages = [(c.topic, json.loads(m.data)) for _, c, m in reader.iter_messages()]
        attachments = [a.name for a in reader.iter_attachments()]
    assert 55 <= counts["/joint_states"] <= 61, counts
    assert counts["/tool_pose"] == counts["/tf"] == counts["/joint_states"] == counts["/clearance"]
    assert 2 <= counts["/body"] < counts["/joint_states"]  # the start, and the first pose
    assert 3 <= counts["/log"] <= 4
    assert attachments == ["robot.urdf"] and counts["/robot_description"] == 1
    status = [m for t, m in messages if t == "/log"][0]["message"]
    assert status.startswith("robot ranger-mk1 (6 joints); mode off (0)"), status
    tf = [m for t, m in messages if t == "/tf"][-1]["transforms"]
    assert [x["child_frame_id"] for x in tf][-1] == "tool"
    pose = [m for t, m in messages if t == "/tool_pose"][-1]["pose"]["position"]
    # /tf is a chain of transforms: the tool's world position is their composition.
    world = compose(tf)
    assert [pose["x"], pose["y"], pose["z"]] == pytest.approx(world, abs=1e-6)


def compose(transforms: list) -> list:
    """The world position of the last child of a chain of foxglove.FrameTransform."""
    def rotate(q: dict, v: list) -> list:
        x, y, z, w = q["x"], q["y"], q["z"], q["w"]
        # v + 2w(u x v) + 2u x (u x v), u = (x, y, z)
        u = [x, y, z]
        c1 = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
        c2 = [u[1] * c1[2] - u[2] * c1[1], u[2] * c1[0] - u[0] * c1[2], u[0] * c1[1] - u[1] * c1[0]]
        return [v[i] + 2 * w * c1[i] + 2 * c2[i] for i in range(3)]

    def multiply(a: dict, b: dict) -> dict:
        return {
            "w": a["w"] * b["w"] - a["x"] * b["x"] - a["y"] * b["y"] - a["z"] * b["z"],
            "x": a["w"] * b["x"] + a["x"] * b["w"] + a["y"] * b["z"] - a["z"] * b["y"],
            "y": a["w"] * b["y"] - a["x"] * b["z"] + a["y"] * b["w"] + a["z"] * b["x"],
            "z": a["w"] * b["z"] + a["x"] * b["y"] - a["y"] * b["x"] + a["z"] * b["w"],
        }

    position = [0.0, 0.0, 0.0]
    rotation = {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}
    for transform in transforms:
        t = transform["translation"]
        step = rotate(rotation, [t["x"], t["y"], t["z"]])
        position = [position[i] + step[i] for i in range(3)]
        rotation = multiply(rotation, transform["rotation"])
    return position


# The colours of /body (viz/src/body_scene.rs): the body, and the nearest pair by its gap.
BODY_COLOR = {"r": 0.35, "g": 0.55, "b": 0.8, "a": 0.35}
WITHIN, NEAR, CLEAR = ({"r": 0.9, "g": 0.1, "b": 0.1, "a": 0.8}, {"r": 1.0, "g": 0.65, "b": 0.0, "a": 0.8},
                       {"r": 0.2, "g": 0.75, "b": 0.3, "a": 0.6})
NEAR_M = 0.05
THINNEST = 0.003


def urdf_capsules(urdf: bytes) -> dict:
    """capsule number -> (link, end a, end b, radius) from the URDF's collision spheres."""
    capsules = {}
    for link in ElementTree.fromstring(urdf).iter("link"):
        for collision in link.iter("collision"):
            name = collision.get("name")
            if name.endswith("_a"):
                k = int(name.split("_")[1])
                b = link.find(f"collision[@name='capsule_{k}_b']")
                point = lambda c: [float(v) for v in c.find("origin").get("xyz").split()]  # noqa: E731
                radius = float(collision.find("geometry/sphere").get("radius"))
                capsules[k] = (link.get("name"), point(collision), point(b), radius)
    return capsules


def link_poses(transforms: list) -> dict:
    """child frame -> 4x4 world pose, composing a chain of foxglove.FrameTransform."""
    def matrix(t: dict) -> list:
        x, y, z, w = (t["rotation"][k] for k in "xyzw")
        r = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
             [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
             [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
        p = [t["translation"][k] for k in "xyz"]
        return [r[i] + [p[i]] for i in range(3)] + [[0.0, 0.0, 0.0, 1.0]]

    poses = {"world": [[float(i == j) for j in range(4)] for i in range(4)]}
    for t in transforms:
        a, b = poses[t["parent_frame_id"]], matrix(t)
        poses[t["child_frame_id"]] = [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)]
                                      for i in range(4)]
    return poses


def sampled(a: list, b: list, n: int) -> list:
    return [[a[i] + (b[i] - a[i]) * s / n for i in range(3)] for s in range(n + 1)]


def test_the_body_is_drawn_with_the_nearest_pair_coloured(recording: dict) -> None:
    """/body: the URDF's capsules (same ends and radii) frame-locked to their links, the
    nearest pair of every pose coloured by its gap (red within the margin, amber within 5 cm
    beyond it, green farther), the others blue-grey; written at the start and on changes only.
    The nearest gap /clearance states is recomputed here from /tf and the capsules, by
    sampling the axes (1 mm apart), for the poses where the nearest pair changes."""
    urdf = recording["attachments"][0].data
    capsules = urdf_capsules(urdf)
    boxes = [[-0.2, 0.2, -0.2, 0.2, -0.1, 0.35]]  # robots/ranger-mk1.toml
    timed = [(t, m.log_time, json.loads(m.data)) for t, m in recording["messages"]
             if t in ("/body", "/clearance", "/tf")]
    scenes = [(time_, p) for t, time_, p in timed if t == "/body"]
    clearances = [p for t, _, p in timed if t == "/clearance"]
    assert scenes[0][0] == 0 and len(clearances) > 500
    assert 2 <= len(scenes) < len(clearances) / 10, len(scenes)
    for _, scene in scenes:
        assert scene["deletions"] == [{"timestamp": scene["deletions"][0]["timestamp"], "type": 1, "id": ""}]
        drawn = {}
        for entity in scene["entities"]:
            if entity["id"] == "nearest_box":
                continue
            assert entity["frame_locked"] and entity["id"] == "body_" + entity["frame_id"]
            numbers = [int(k) for k in entity["metadata"][0]["value"].split()]
            spheres = entity["spheres"]
            for k, (a, b) in zip(numbers, zip(spheres[0::2], spheres[1::2])):
                drawn[k] = (entity["frame_id"], [a["pose"]["position"][c] for c in "xyz"],
                            [b["pose"]["position"][c] for c in "xyz"], a["size"]["x"] / 2)
        assert drawn.keys() == capsules.keys()
        for k, (link, a, b, r) in capsules.items():
            assert drawn[k][0] == link
            assert drawn[k][1] == pytest.approx(a, abs=1e-12) and drawn[k][2] == pytest.approx(b, abs=1e-12)
            assert drawn[k][3] == pytest.approx(max(r, THINNEST), abs=1e-12)

    # /clearance comes before its tick's /body: the scene of a time is the last one written then.
    scene_at = {time_: p for time_, p in scenes}
    scene, tf, checked, kinds = scenes[0][1], None, 0, set()
    for t, time_, c in timed:
        if t == "/tf":
            tf = c["transforms"]
        if t != "/clearance":
            continue
        changed = time_ in scene_at and scene_at[time_] is not scene
        scene = scene_at.get(time_, scene)
        margin, gap = c["margin"], c["nearest"]
        colour = WITHIN if gap <= margin else NEAR if gap <= margin + NEAR_M else CLEAR
        pair = {c["link"]} | ({int(c["obstacle"][1:])} if c["obstacle"].startswith("L") else set())
        for entity in scene["entities"]:
            if entity["id"] == "nearest_box":
                assert c["obstacle"] == "B1" and entity["cubes"][0]["color"] == colour
                continue
            link = 0 if entity["frame_id"] == "base_link" else int(entity["frame_id"].split("_")[1])
            expected = colour if link in pair else BODY_COLOR
            assert all(s["color"] == expected for s in entity["spheres"] + entity["cylinders"])
        assert ("nearest_box" in [e["id"] for e in scene["entities"]]) == (c["obstacle"] == "B1")
        assert min(v for v in (c["boxes"], c["bounds"], c["links"]) if v is not None) == gap
        kinds.add(c["obstacle"])
        if changed and checked < 6:
            checked += 1
            poses = link_poses(tf)

            def world(k: int) -> tuple:
                link, a, b, r = capsules[k]
                m = poses[link]
                at = lambda p: [sum(m[i][j] * p[j] for j in range(3)) + m[i][3] for i in range(3)]  # noqa: E731
                return at(a), at(b), r

            ours = [k for k, cap in capsules.items() if
                    (0 if cap[0] == "base_link" else int(cap[0].split("_")[1])) == c["link"]]
            best = math.inf
            for k in ours:
                a, b, r = world(k)
                points = sampled(a, b, max(1, int(math.dist(a, b) / 0.001)))
                if c["obstacle"].startswith("B"):
                    bx = boxes[int(c["obstacle"][1:]) - 1]
                    for p in points:
                        d = math.dist(p, [min(max(p[i], bx[2 * i]), bx[2 * i + 1]) for i in range(3)])
                        best = min(best, d - r)
                elif c["obstacle"].startswith("L"):
                    other = int(c["obstacle"][1:])
                    for j, cap in capsules.items():
                        if (0 if cap[0] == "base_link" else int(cap[0].split("_")[1])) != other:
                            continue
                        a2, b2, r2 = world(j)
                        others = sampled(a2, b2, max(1, int(math.dist(a2, b2) / 0.001)))
                        best = min(best, min(math.dist(p, q) for p in points for q in others) - r - r2)
            if best < math.inf:
                assert best == pytest.approx(gap, abs=1e-3), (c, best)
    assert checked >= 1
    print(f"/body: {len(scenes)} scenes for {len(clearances)} poses; nearest: {sorted(kinds)}")
