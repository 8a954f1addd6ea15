"""``armgate-sim --mcap``: a 20 s run read back by an independent reader (the ``mcap`` package
from PyPI): every channel with its schema, the expected message counts, joint states at the
tick rate, monotonic log times (the simulation's), the URDF as attachment and channel.

Skipped without the ``mcap`` package, unless ``ARMGATE_REQUIRE_VIZ=1`` (CI sets it).
"""

from __future__ import annotations

import base64
import json
import signal
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
            "metadata": metadata, "sent": sent, "port": sim.port, "stderr": stderr.decode()}


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
    assert counts["/tf"] == counts["/tool_pose"] == counts["/joint_states"]
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
    assert counts["/tool_pose"] == counts["/tf"] == counts["/joint_states"]
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
