"""Signed datagrams (docs/safety.md, "Signing"): the block's bytes against the Rust side's
known answers, and the signed client against ``armgate-sim --key``."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

import armgate
from armgate import signing, wire

TEST_KEY = bytes(range(32))


def test_the_block_matches_the_rust_known_answers() -> None:
    # protocol/src/client/signed/block.rs: SIGNED_BG and SIGNED_GB.
    bg = signing.sign(TEST_KEY, wire.encode("BG"), 1, 0x0123456789AB)
    assert bg.hex() == (
        "4247" + "00" * 29 + "01" + "ab8967452301" + "b224bae2fc46"
    )
    gb = signing.sign(TEST_KEY, wire.encode("GB"), 0, 0x0123456789AC)
    assert gb.hex().endswith("00" + "ac8967452301" + "2afe02a8d44f")
    assert signing.verify(TEST_KEY, bg) == (1, 0x0123456789AB)
    assert signing.verify(TEST_KEY, bg[:-1]) is None
    altered = bytes([bg[0] ^ 1]) + bg[1:]
    assert signing.verify(TEST_KEY, altered) is None


def test_timestamps_increase_and_answers_must_be_the_controllers_and_fresh() -> None:
    signer = signing.Signer(TEST_KEY, link_id=3)
    first, t1 = signer.sign(wire.encode("PS"))
    _, t2 = signer.sign(wire.encode("PS"))
    assert t2 > t1 > 11 * 365 * 86_400 * 100_000
    assert first[31] == 3
    answer = signing.sign(TEST_KEY, wire.encode("SP"), 0, t2)
    assert signer.open(answer, t2) == answer[:31]
    assert signer.open(answer, t2 + 1) is None
    assert signer.open(signing.sign(TEST_KEY, wire.encode("SP"), 3, t2), t2) is None
    with pytest.raises(ValueError):
        signing.Signer(TEST_KEY, link_id=0)


@pytest.fixture
def key_file(tmp_path: Path) -> Path:
    path = tmp_path / "arm.key"
    path.write_text("# lab arm\n" + os.urandom(32).hex() + "\n")
    path.chmod(0o600)
    return path


def test_a_signed_client_commands_a_keyed_controller_and_others_get_silence(
    sim_factory, key_file: Path, tmp_path: Path  # type: ignore[no-untyped-def]
) -> None:
    sim = sim_factory("ranger-mk1", "--key", str(key_file))
    with armgate.Arm("127.0.0.1", sim.port, key=key_file) as arm:
        home = arm.get_joints()
        arm.set_mode("joint")
        goal = list(home)
        goal[0] += 0.02
        arm.move_j(goal)
        assert abs(arm.get_joints()[0] - goal[0]) < 1e-3
    # Unsigned, or signed with another key: dropped, never answered.
    with armgate.Arm("127.0.0.1", sim.port, timeout=0.1, retries=0, joints=6) as legacy:
        with pytest.raises(armgate.ReplyTimeout):
            legacy.get_tcp_pose()
    other = tmp_path / "other.key"
    other.write_text(os.urandom(32).hex())
    with armgate.Arm("127.0.0.1", sim.port, timeout=0.1, retries=0, joints=6, key=other) as wrong:
        with pytest.raises(armgate.ReplyTimeout):
            wrong.get_tcp_pose()
    with armgate.Arm("127.0.0.1", sim.port, key=key_file, link_id=9) as arm:
        counts = arm.request("SQ", index=4).values
    # Policy 1 (required), an unsigned and a forged (other key) datagram dropped.
    assert counts[0] == 1.0
    assert counts[3] == 1.0
    assert counts[5] == 1.0


def test_a_signed_client_says_when_the_controller_answers_unsigned(mk1, key_file: Path) -> None:  # type: ignore[no-untyped-def]
    with armgate.Arm("127.0.0.1", mk1.port, timeout=0.1, retries=0, joints=6, key=key_file) as arm:
        with pytest.raises(armgate.SignatureMismatch):
            arm.get_tcp_pose()
