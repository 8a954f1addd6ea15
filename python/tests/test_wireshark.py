"""``armgate-sim --pcap`` and tools/wireshark/armgate.lua: a capture of known requests, decoded
by tshark, field by field.

Skipped without tshark, unless ``ARMGATE_REQUIRE_TSHARK=1`` (CI sets it): then it fails.
"""

from __future__ import annotations

import os
import shutil
import signal
import struct
import subprocess
from pathlib import Path
from typing import List

import pytest

import armgate
from conftest import REPO, Sim

DISSECTOR = REPO / "tools" / "wireshark" / "armgate.lua"


@pytest.fixture(scope="module")
def tshark() -> str:
    found = shutil.which("tshark")
    if found is None:
        if os.environ.get("ARMGATE_REQUIRE_TSHARK") == "1":
            pytest.fail("tshark is not installed (apt-get install tshark)")
        pytest.skip("tshark is not installed")
    return found


@pytest.fixture(scope="module")
def capture(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """An 8-joint arm (both joint banks), a few requests, then SIGTERM: the file is flushed."""
    path = tmp_path_factory.mktemp("pcap") / "armgate.pcapng"
    sim = Sim("ranger-mk2", ["--pcap", str(path)])
    with armgate.Arm("127.0.0.1", port=sim.port) as arm:
        arm.set_mode("cartesian")
        arm.request("GT", [0.25, -0.125, 1.0, 0.0, 0.5, 0.0, 2.5])
        arm.set_mode("joint")
        with pytest.raises(armgate.CommandRejected):
            arm.request("BG")
        joints = arm.get_joints()  # two jP: bank 1 and bank 2
        arm.request("jV", [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 1.5], index=0x83)
    sim.process.send_signal(signal.SIGTERM)
    _, stderr = sim.process.communicate(timeout=20)
    return {"path": path, "port": sim.port, "joints": joints, "stderr": stderr.decode()}


def fields(tshark: str, capture: dict, display_filter: str, *names: str) -> List[List[str]]:
    out = subprocess.run(
        [tshark, "-X", f"lua_script:{DISSECTOR}", "-o", f"armgate.port:{capture['port']}",
         "-r", str(capture["path"]), "-Y", display_filter, "-T", "fields",
         *[arg for name in names for arg in ("-e", name)]],
        capture_output=True, text=True, check=True,
    ).stdout
    return [line.split("\t") for line in out.splitlines()]


def f32(v: float) -> float:
    return struct.unpack("<f", struct.pack("<f", v))[0]


def test_the_capture_is_flushed_on_sigterm(capture: dict) -> None:
    assert "packets captured, 0 dropped" in capture["stderr"], capture["stderr"]
    assert capture["path"].stat().st_size > 1000


def test_client_requests_and_replies_are_decoded(tshark: str, capture: dict) -> None:
    gt = fields(tshark, capture, 'armgate.command == "GT"', "armgate.direction",
                "armgate.x", "armgate.y", "armgate.pitch", "armgate.time", "udp.dstport")
    assert len(gt) == 1
    direction, x, y, pitch, t, port = gt[0]
    assert direction == "request" and int(port) == capture["port"]
    assert (float(x), float(y), float(pitch), float(t)) == (0.25, -0.125, 0.5, 2.5)
    # The echo is a reply with the same values.
    tg = fields(tshark, capture, 'armgate.command == "TG"', "armgate.direction", "armgate.time")
    assert tg == [["reply", "2.5"]]
    mode = fields(tshark, capture, 'armgate.command == "MC"', "armgate.mode")
    assert [float(m[0]) for m in mode] == [2.0, 1.0]


def test_error_texts_are_decoded(tshark: str, capture: dict) -> None:
    rows = fields(tshark, capture, "armgate.severity", "armgate.text", "armgate.code",
                  "armgate.reason")
    assert ["ER20 Cmd BG rejected", "20", "Cmd BG rejected"] in rows


def test_joint_banks_are_decoded(tshark: str, capture: dict) -> None:
    rows = fields(tshark, capture, 'armgate.command == "Pj"', "armgate.bank2", "armgate.joint")
    assert len(rows) == 2
    (bank1, bank1_joints), (bank2, bank2_joints) = rows
    assert bank1 in ("0", "False") and bank2 in ("1", "True")
    q = capture["joints"]
    assert [float(v) for v in bank1_joints.split(",")] == pytest.approx(q[:7], abs=1e-6)
    assert float(bank2_joints.split(",")[1]) == pytest.approx(q[7], abs=1e-6)
    jv = fields(tshark, capture, 'armgate.command == "jV"', "armgate.slot", "armgate.bank2",
                "armgate.joint", "armgate.time")
    assert jv[0][0] == "3" and jv[0][1] in ("1", "True")
    assert [float(v) for v in jv[0][2].split(",")] == pytest.approx([f32(v) for v in
                                                                     (0.1, 0.2, 0.3, 0.4, 0.5, 0.6)])
    assert float(jv[0][3]) == 1.5


def test_can_traffic_is_decoded(tshark: str, capture: dict) -> None:
    # PT writes go to every drive of ranger-mk2 (nodes 101..108), QP slots 1..6.
    writes = fields(tshark, capture, 'armgate_can.kind == "PT write"', "armgate_can.node",
                    "armgate_can.pt.slot", "armgate_can.mnemonic")
    assert {int(w[0]) for w in writes} == set(range(101, 109))
    assert {int(w[1]) for w in writes} <= set(range(1, 7))
    assert {w[2] for w in writes} == {"QP"}
    # The start: NMT start to all nodes, the consumer heartbeat by SDO, the controller's
    # heartbeat (node 127, operational), and interpreter replies.
    nmt = fields(tshark, capture, "armgate_can.nmt.command", "armgate_can.nmt.command",
                 "armgate_can.nmt.node")
    assert ["0x01", "0"] in nmt
    sdo = fields(tshark, capture, "armgate_can.sdo.object == 0x1016", "armgate_can.sdo.data")
    assert ["0x007f012c"] in [[v.lower() for v in row] for row in sdo]
    heartbeats = fields(tshark, capture, "armgate_can.heartbeat.state", "armgate_can.node",
                        "armgate_can.heartbeat.state")
    assert ["127", "0x05"] in heartbeats
    replies = fields(tshark, capture, 'armgate_can.kind == "reply"', "armgate_can.mnemonic")
    assert {"PX", "UM", "MO"} <= {r[0] for r in replies}
