"""``armgate-sim --pcap`` and tools/wireshark/armgate.lua: a capture of known requests, decoded
by tshark, field by field.

Skipped without tshark, unless ``ARMGATE_REQUIRE_TSHARK=1`` (CI sets it): then it fails.
"""

from __future__ import annotations

import os
import shutil
import signal
import socket
import struct
import subprocess
from pathlib import Path
from typing import List, Optional

import pytest

import armgate
from armgate import signing
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
        try:
            arm.twist([0.01, 0.0, -0.02], [0.0, 0.0, 0.5], tool_frame=True)
        except armgate.CommandRejected:
            pass  # the drives may still be starting: the request is what is decoded here
        arm.set_mode("joint")
        with pytest.raises(armgate.CommandRejected):
            arm.request("BG")
        joints = arm.get_joints()  # two jP: bank 1 and bank 2
        arm.request("jV", [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 1.5], index=0x83)
        arm.request("VT", [0.01, 0, 0, 0, 0, 0, 0], index=2)
    sim.process.send_signal(signal.SIGTERM)
    _, stderr = sim.process.communicate(timeout=20)
    return {"path": path, "port": sim.port, "joints": joints, "stderr": stderr.decode()}


def own_address() -> Optional[str]:
    """This machine's non-loopback IPv4 address (no packet is sent to find it), if any."""
    probe = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        probe.connect(("192.0.2.1", 9))
        address: str = probe.getsockname()[0]
    except OSError:
        return None
    finally:
        probe.close()
    return None if address.startswith("127.") else address


def test_datagrams_from_refused_sources_are_captured(tshark: str, tmp_path: Path) -> None:
    # --allow adds to loopback, so the refused source is this machine's own network address
    # (sending to the loopback listener), outside both loopback and the documentation range
    # allowed here.
    own = own_address()
    if own is None:
        pytest.skip("this machine has no address besides loopback")
    path = tmp_path / "refused.pcapng"
    sim = Sim("ranger-mk1", ["--pcap", str(path), "--allow", "198.51.100.0/24"])
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as foreign:
        foreign.bind((own, 0))
        foreign.settimeout(0.3)
        foreign.sendto(b"PS" + bytes(29), ("127.0.0.1", sim.port))
        with pytest.raises(socket.timeout):
            foreign.recv(64)
    sim.process.send_signal(signal.SIGTERM)
    sim.process.communicate(timeout=20)
    capture = {"path": path, "port": sim.port}
    rows = fields(tshark, capture, f"armgate && ip.src == {own}", "armgate.command")
    assert rows == [["PS"]], "captured once, and not answered"
    assert fields(tshark, capture, f"armgate && ip.dst == {own}", "armgate.command") == []


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
    refusals = [r for r in rows if r[0].startswith("ER20 Cmd BG ")]
    assert len(refusals) == 1
    text, code, reason = refusals[0]
    assert code == "20" and reason == text[5:]


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


def test_blend_tolerances_are_decoded(tshark: str, capture: dict) -> None:
    rows = fields(tshark, capture, 'armgate.command == "VT" || armgate.command == "TV"',
                  "armgate.command", "armgate.blend", "armgate.slot")
    assert [(c, s) for c, _, s in rows] == [("VT", "2"), ("TV", "2")]
    assert [float(b) for _, b, _ in rows] == pytest.approx([0.01, 0.01], abs=1e-9)


def test_twists_are_decoded(tshark: str, capture: dict) -> None:
    rows = fields(tshark, capture, 'armgate.command == "TW"', "armgate.vx", "armgate.vz",
                  "armgate.wz", "armgate.tool_frame")
    assert len(rows) == 1
    vx, vz, wz, tool = rows[0]
    assert (float(vx), float(vz), float(wz)) == pytest.approx((f32(0.01), f32(-0.02), 0.5))
    assert tool in ("1", "True")


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


# -- frames the simulator does not send on its own: faults, SYNC, floats, the status reply ----


def _block(kind: int, body: bytes) -> bytes:
    body += b"\0" * (-len(body) % 4)
    return struct.pack("<II", kind, len(body) + 12) + body + struct.pack("<I", len(body) + 12)


def _pcapng(packets: List[tuple]) -> bytes:
    """A pcapng file: interface 0 raw IP (LINKTYPE_RAW), 1 SocketCAN; ``packets`` are
    ``(interface, bytes)``."""
    out = _block(0x0A0D0D0A, struct.pack("<IHHq", 0x1A2B3C4D, 1, 0, -1))
    out += _block(1, struct.pack("<HHI", 101, 0, 0)) + _block(1, struct.pack("<HHI", 227, 0, 0))
    for k, (interface, data) in enumerate(packets):
        out += _block(6, struct.pack("<IIIII", interface, 0, k, len(data), len(data)) + data)
    return out


def _udp(src_port: int, dst_port: int, payload: bytes) -> tuple:
    udp = struct.pack(">HHHH", src_port, dst_port, 8 + len(payload), 0) + payload
    ip = struct.pack(">BBHHHBBH4s4s", 0x45, 0, 20 + len(udp), 0, 0x4000, 64, 17, 0,
                     bytes([127, 0, 0, 1]), bytes([127, 0, 0, 1]))
    return (0, ip + udp)


def _can(can_id: int, data: bytes) -> tuple:
    return (1, struct.pack(">IB3x", can_id, len(data)) + data.ljust(8, b"\0"))


@pytest.fixture(scope="module")
def crafted(tmp_path_factory: pytest.TempPathFactory) -> dict:
    status = wire_reply("QS", [2, 4, 33, 8, 0, 3, 12.5], 0)
    name = b"QS" + b"ranger-mk2".ljust(28, b"\0") + b"\x01"
    packets = [
        _udp(7031, 40000, status),                                       # 1
        _udp(7031, 40000, name),                                         # 2
        _udp(7031, 40000, b"WN27 Via point missed.".ljust(31, b"\0")),   # 3
        _can(0x085, bytes([0x00, 0xFF, 0x81, 0x08, 0x05, 0x00, 0x03, 0x00])),  # 4 EMCY underflow
        _can(0x082, bytes([0x30, 0x81, 0x11, 0, 0, 0, 0, 0])),           # 5 EMCY heartbeat lost
        _can(0x080, b""),                                                # 6 SYNC
        _can(0x2E6, b"QP\x03\x40\x15\0\0\0"),                            # 7 error reply, EC 21
        _can(0x366, b"TC\0\x80" + struct.pack("<f", 1.5)),               # 8 float set
        _can(0x5E6, b"\x80\x16\x10\x01" + struct.pack("<I", 0x06090011)),  # 9 SDO abort
        _can(0x000, b"\x81\x00"),                                        # 10 NMT reset node, all
        _can(0x465, struct.pack("<i", -12345)),                          # 11 RPDO3 PT point
        _can(0x3E5, struct.pack("<iHH", 12345, 5, 2)),                   # 12 TPDO3 feedback
        _can(0x0E5, bytes([0x00, 0xFF, 0x81, 0x5C, 0x65, 0x04, 0, 0])),  # 13 EMCY PDO not mapped
        _can(0x665, bytes([0x23, 0x02, 0x16, 0x01, 0x20, 0x00, 0x02, 0x20])),  # 14 map 0x2002
        _can(0x100, struct.pack("<I", 4_000_000_123)),                   # 15 Time Stamp
        # 16: a signed BG (the known answer of protocol/src/client/signed/block.rs), 17: a
        # signed notice from the controller (link 0) at 2026-01-01 00:00:00 UTC, 18: a cut-off
        # block, 19: the signing counters (QS index 4).
        _udp(40000, 7031, signing.sign(bytes(range(32)), armgate.wire.encode("BG"), 1,
                                       0x0123456789AB, 0xED0A5E0C)),
        _udp(7031, 40000, signing.sign(bytes(range(32)),
                                       b"WN27 Via point missed.".ljust(31, b"\0"), 0,
                                       (1_767_225_600 - 1_420_070_400) * 100_000)),
        _udp(40000, 7031, armgate.wire.encode("PS") + b"\x01\x02\x03"),
        _udp(7031, 40000, wire_reply("QS", [1, 12, 0, 1, 2, 3, 4], 4)),
        # 20: the nearest gap (QS index 7): link 6, 12.5 mm from box 1; 21: a stream held
        # before that contact.
        _udp(7031, 40000, wire_reply("QS", [0.0125, 6, 0, 1, 0, 0, 0], 7)),
        _udp(7031, 40000, b"WN13 Held: L6 hits B1".ljust(31, b"\0")),
    ]
    path = tmp_path_factory.mktemp("crafted") / "crafted.pcapng"
    path.write_bytes(_pcapng(packets))
    return {"path": path, "port": 7031}


def wire_reply(chars: str, values: List[float], index: int) -> bytes:
    return armgate.wire.encode(chars, values, index)


def test_the_status_reply_is_decoded(tshark: str, crafted: dict) -> None:
    rows = fields(tshark, crafted, "frame.number <= 2", "armgate.command", "armgate.status.drives",
                  "armgate.status.fault", "armgate.status.joints", "armgate.status.uptime",
                  "armgate.status.name")
    assert rows[0][:5] == ["QS", "4", "33", "8", "12.5"]
    assert rows[1][0] == "QS" and rows[1][5] == "ranger-mk2"
    text = fields(tshark, crafted, "frame.number == 3", "armgate.severity", "armgate.code")
    assert text == [["warning", "27"]]


def test_the_nearest_gap_and_a_held_stream_are_decoded(tshark: str, crafted: dict) -> None:
    rows = fields(tshark, crafted, "frame.number >= 20", "armgate.nearest.link",
                  "armgate.nearest.kind", "armgate.nearest.number", "armgate.code",
                  "armgate.reason", "_ws.col.Info")
    assert rows[0][:3] == ["6", "0", "1"]
    assert "nearest=12.5 mm L6 B1" in rows[0][5]
    assert rows[1][3:5] == ["13", "Held: L6 hits B1"]


def test_emergencies_and_other_frames_are_decoded(tshark: str, crafted: dict) -> None:
    def row(n: int, *names: str) -> List[str]:
        return fields(tshark, crafted, f"frame.number == {n}", *names)[0]

    node, code, meaning = row(4, "armgate_can.node", "armgate_can.emcy.code",
                              "armgate_can.emcy.meaning")
    assert (node, code) == ("5", "0xff00")
    assert "underflow" in meaning and "ER33" in meaning
    assert "ER36" in row(5, "armgate_can.emcy.meaning")[0]
    assert row(6, "armgate_can.service") == ["SYNC"]
    assert row(7, "armgate_can.node", "armgate_can.kind", "armgate_can.error_code") == [
        "102", "error reply", "21"]
    assert row(8, "armgate_can.mnemonic", "armgate_can.float") == ["TC", "1.5"]
    assert row(9, "armgate_can.sdo.abort") == ["0x06090011"]
    assert row(10, "armgate_can.nmt.command", "armgate_can.nmt.node") == ["0x81", "0"]


def test_pdo_streaming_frames_are_decoded(tshark: str, crafted: dict) -> None:
    def row(n: int, *names: str) -> List[str]:
        return fields(tshark, crafted, f"frame.number == {n}", *names)[0]

    assert row(11, "armgate_can.node", "armgate_can.pt.counts") == ["101", "-12345"]
    assert row(12, "armgate_can.feedback.position", "armgate_can.feedback.head",
               "armgate_can.feedback.tail") == ["12345", "5", "2"]
    assert "PDO not mapped" in row(13, "armgate_can.emcy.meaning")[0]
    assert row(14, "armgate_can.sdo.object", "armgate_can.meaning") == ["0x1602", "RPDO3 mapping"]
    assert row(15, "armgate_can.service", "armgate_can.time_stamp.micros") == [
        "Time Stamp", "4000000123"]


def test_signature_blocks_are_decoded(tshark: str, crafted: dict) -> None:
    def row(n: int, *names: str) -> List[str]:
        return fields(tshark, crafted, f"frame.number == {n}", *names)[0]

    assert row(16, "armgate.command", "armgate.signature.link", "armgate.signature.timestamp",
               "armgate.signature.tag") == ["BG", "1", str(0x0123456789AB), "6efbddaa1201"]
    assert row(17, "armgate.text", "armgate.signature.link", "armgate.signature.time") == [
        "WN27 Via point missed.", "0", "2026-01-01 00:00:00"]
    info = fields(tshark, crafted, "frame.number == 18", "_ws.col.Info")[0][0]
    assert "signature truncated" in info
    assert row(19, "armgate.signing.policy", "armgate.signing.signed",
               "armgate.signing.dropped_forged", "armgate.signing.dropped_replayed") == [
        "1", "12", "3", "4"]
