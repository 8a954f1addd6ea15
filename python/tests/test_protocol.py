"""Matching, retries, notices and the status layout, against a scripted fake controller."""

from __future__ import annotations

import struct
from typing import List

import pytest

import armgate
from armgate import wire
from conftest import reply, text


def echo(datagram: bytes) -> List[bytes]:
    """A null reply with the request's characters reversed and its index."""
    return [reply(datagram[:2].decode()[::-1], index=datagram[30])]


def test_an_address_may_be_host_port_and_a_bad_one_says_so() -> None:
    with armgate.Arm("127.0.0.1:7203") as arm:
        assert arm._socket.getpeername() == ("127.0.0.1", 7203)
    with armgate.Arm("[::1]:7203") as arm:
        assert arm._socket.getpeername()[:2] == ("::1", 7203)
    with pytest.raises(ValueError, match="expected Arm"):
        armgate.Arm("no-such-host.invalid")


def test_messages_are_31_bytes_little_endian() -> None:
    datagram = wire.encode("jV", [1.5, -2.0], index=0x83)
    assert len(datagram) == 31
    assert datagram[:2] == b"jV"
    assert struct.unpack_from("<2f", datagram, 2) == (1.5, -2.0)
    assert datagram[30] == 0x83
    assert wire.text_of(text("WN12 Joint limit.")) == "WN12 Joint limit."
    assert wire.text_of(datagram) is None


def test_texts_map_to_classes_with_code_and_reason() -> None:
    cases = {
        "ER00 Cmd XY not understood": armgate.NotUnderstood,
        "ER01 Msg B? undersized.": armgate.Undersized,
        "ER20 Cmd BG rejected": armgate.CommandRejected,
        "ER21 Work space limit.": armgate.WorkspaceLimit,
        "ER33 J4 PT buffer underflow": armgate.DriveFault,
        "WN12 Joint limit.": armgate.JointLimitWarning,
        "WN22 Inv Kin Divergence.": armgate.IkDivergence,
        "WN27 Via point missed.": armgate.ViaPointMissed,
        "ER99 something new": armgate.ControllerError,
    }
    for t, kind in cases.items():
        e = armgate.ControllerMessage.from_text(t)
        assert type(e) is kind, t
        assert e.text == t and e.code == int(t[2:4]) and e.reason == t[5:]
    refusal = armgate.ControllerMessage.from_text("ER20 Cmd BG needs mode 2")
    assert (refusal.command, refusal.detail) == ("BG", "needs mode 2")
    fault = armgate.ControllerMessage.from_text("ER33 J4 PT buffer underflow")
    assert isinstance(fault, armgate.DriveFault) and fault.joint == 4 and fault.ends_motion
    assert not armgate.ControllerMessage.from_text("WN12 Joint limit.").ends_motion
    assert armgate.ControllerMessage.from_text("WN27 Via point missed.").ends_motion


def test_notices_before_the_reply_go_to_the_callback(fake_factory) -> None:  # type: ignore[no-untyped-def]
    fake = fake_factory(
        lambda d: [
            text("WN12 Joint limit."),
            text("ER20 Cmd jB rejected"),  # a refusal of another request: a notice here
            reply("TS"),  # stale
            reply("SP", [0.5, 0.2, 0.1, 0, 0, 0, 1]),
        ]
    )
    seen: List[armgate.ControllerMessage] = []
    with armgate.Arm("127.0.0.1", fake.port, on_notice=seen.append) as arm:
        pose = arm.get_tcp_pose()
        assert pose.xyz == pytest.approx((0.5, 0.2, 0.1))
        assert [type(n) for n in seen] == [armgate.JointLimitWarning, armgate.CommandRejected]
        assert seen[0].code == 12
        assert arm.stale_replies == 1
        assert [n.text for n in arm.take_notices()] == ["WN12 Joint limit.", "ER20 Cmd jB rejected"]
    assert len(fake.received) == 1


def test_a_lost_request_is_retried(fake_factory) -> None:  # type: ignore[no-untyped-def]
    count = []

    def drop_first(d: bytes) -> List[bytes]:
        count.append(d)
        return [] if len(count) == 1 else echo(d)

    fake = fake_factory(drop_first)
    with armgate.Arm("127.0.0.1", fake.port, timeout=0.1) as arm:
        arm.stop()
    assert fake.received == [wire.encode("ST")] * 2


def test_silence_times_out_after_every_retry(fake_factory) -> None:  # type: ignore[no-untyped-def]
    fake = fake_factory(lambda d: [])
    with armgate.Arm("127.0.0.1", fake.port, timeout=0.03, retries=3) as arm:
        with pytest.raises(armgate.ReplyTimeout) as e:
            arm.stop()
    assert e.value.attempts == 4 and e.value.command == "ST"
    assert len(fake.received) == 4


def test_refusals_are_not_retried(fake_factory) -> None:  # type: ignore[no-untyped-def]
    fake = fake_factory(lambda d: [text("ER11 Arm did not start")])
    with armgate.Arm("127.0.0.1", fake.port) as arm:
        with pytest.raises(armgate.ArmDidNotStart):
            arm.on()
    assert len(fake.received) == 1


def test_index_echo_is_matched(fake_factory) -> None:  # type: ignore[no-untyped-def]
    # jP bank 2 must be answered with bit 7 set: a bank-1 answer is stale.
    def answer(d: bytes) -> List[bytes]:
        index = d[30]
        return [reply("Pj", [9.0] * 7, 0), reply("Pj", [7.0, 8.0], index)]

    fake = fake_factory(answer)
    with armgate.Arm("127.0.0.1", fake.port, joints=8) as arm:
        assert arm.get_joints() == [9.0] * 7 + [8.0]
        # The second answer to the bank-1 read, and the bank-1 answer to the bank-2 read.
        assert arm.stale_replies == 2


def test_eight_joint_writes_send_bank_two_first(fake_factory) -> None:  # type: ignore[no-untyped-def]
    fake = fake_factory(echo)
    with armgate.Arm("127.0.0.1", fake.port, joints=8) as arm:
        arm.request("jC")
        arm._write_banks("jV", [1, 2, 3, 4, 5, 6, 7, 8], 5, 2.5)
    first, second = (wire.decode(d) for d in fake.received[1:])
    assert first.index == 0x85 and first.values == (7, 8, 0, 0, 0, 0, 2.5)
    assert second.index == 0x05 and second.values == (1, 2, 3, 4, 5, 6, 2.5)


def test_a_motion_ending_notice_aborts_the_wait(fake_factory) -> None:  # type: ignore[no-untyped-def]
    polls = []

    def arm_script(d: bytes) -> List[bytes]:
        if d[:2] != b"PS":
            return echo(d)
        polls.append(d)
        out = [text("WN27 Via point missed.")] if len(polls) == 3 else []
        return out + [reply("SP", [0.1 * len(polls), 0, 0, 0, 0, 0, 1])]

    fake = fake_factory(arm_script)
    seen: List[armgate.ControllerMessage] = []
    with armgate.Arm("127.0.0.1", fake.port, on_notice=seen.append) as arm:
        arm.wait_options = armgate.WaitOptions(poll=0.001)
        with pytest.raises(armgate.ViaPointMissed):
            arm.move_l(armgate.Pose(5.0, 0, 0))
    assert [n.code for n in seen] == [27]


def test_a_wait_for_an_arm_that_does_not_move_stalls(fake_factory) -> None:  # type: ignore[no-untyped-def]
    fake = fake_factory(
        lambda d: [reply("SP", [0, 0, 0, 0, 0, 0, 1])] if d[:2] == b"PS" else echo(d)
    )
    with armgate.Arm("127.0.0.1", fake.port) as arm:
        arm.wait_options = armgate.WaitOptions(poll=0.001, stall=0.1)
        with pytest.raises(armgate.Stalled) as e:
            arm.move_l([0.1, 0, 0, 0, 0, 0])
    assert e.value.distance == pytest.approx(0.1)


def test_status_layout(fake_factory) -> None:  # type: ignore[no-untyped-def]
    def answer(d: bytes) -> List[bytes]:
        if d[30] == 0:
            return [reply("QS", [2, 2, 0, 6, 3, 4, 12.5], 0)]
        if d[30] == 2:  # ST from 192.168.1.2:40001
            return [reply("QS", [1, 0, 49320, 258, 40001, 0, 0], 2)]
        if d[30] == 3:  # held by 192.168.1.3:40002, watchdog 500 ms, 2 clients
            return [reply("QS", [2, 49320, 259, 40002, 500, 0, 2], 3)]
        return [b"QS" + b"ranger-mk1".ljust(28, b"\0") + bytes([1])]

    fake = fake_factory(answer)
    with armgate.Arm("127.0.0.1", fake.port) as arm:
        status = arm.get_status()
        assert arm.joint_count == 6
        plain = arm.get_status(details=False)
    assert status == armgate.Status(
        mode=armgate.Mode.CARTESIAN,
        drive_state=armgate.DriveState.RUNNING,
        drive_fault=0,
        joint_count=6,
        motion=armgate.Motion.JOINT_SEQUENCE,
        refusals=4,
        uptime=12.5,
        name="ranger-mk1",
        stop_cause=armgate.StopCause.STOP,
        stopped_by="192.168.1.2:40001",
        holder=armgate.Holder.OTHER,
        holder_address="192.168.1.3:40002",
        watchdog_ms=500,
        clients=2,
    )
    assert plain.holder is None and plain.stop_cause is None


def test_an_older_controller_is_named_as_such(fake_factory) -> None:  # type: ignore[no-untyped-def]
    def answer(d: bytes) -> List[bytes]:
        if d[:2] == b"SQ":
            return [text("ER00 Cmd SQ not understood")]
        # TM: four drives, the rest -1000.
        return [reply("MT", [30, 31, 32, 33, -1000, -1000, -1000])]

    fake = fake_factory(answer)
    with armgate.Arm("127.0.0.1", fake.port) as arm:
        with pytest.raises(armgate.ControllerTooOld, match="SQ"):
            arm.get_status()
        assert arm.joint_count == 4
        assert arm.get_temperatures() == [30, 31, 32, 33]


def test_rpy_round_trips_and_matches_the_gimbal_branch() -> None:
    pose = armgate.Pose.from_rpy(0, 0, 0, 0.3, -0.2, 1.1)
    assert pose.rpy == pytest.approx((0.3, -0.2, 1.1))
    # pitch = pi/2: yaw is reported 0 and the rotation goes to roll.
    gimbal = armgate.Pose.from_rpy(0, 0, 0, 0.0, math_pi_2(), 0.4)
    roll, pitch, yaw = gimbal.rpy
    assert yaw == 0.0 and pitch == pytest.approx(math_pi_2())
    assert armgate.Pose.from_rpy(0, 0, 0, roll, pitch, yaw).angle_to(gimbal) < 1e-6


def math_pi_2() -> float:
    import math

    return math.pi / 2
