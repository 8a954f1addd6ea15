"""Signed datagrams (docs/safety.md, "Signing"): the block's bytes against the Rust side's
known answers, and the signed client against ``armgate-sim --key``."""

from __future__ import annotations

import hashlib
import hmac
import os
import time
from pathlib import Path

import pytest

import armgate
from armgate import signing, wire
from conftest import free_port

TEST_KEY = bytes(range(32))


ARM = 0xED0A5E0C
"""The controller id of the known answers (protocol/src/client/signed/block.rs)."""


def test_the_block_matches_the_rust_known_answers() -> None:
    # protocol/src/client/signed/block.rs: SIGNED_BG and SIGNED_GB, for controller ARM; the
    # tags computed here with hmac directly, and by the package.
    head = b"BG" + bytes(29) + bytes([1]) + (0x0123456789AB).to_bytes(6, "little")
    mac = hmac.new(TEST_KEY, ARM.to_bytes(4, "little") + head, hashlib.sha256).digest()[:6]
    assert mac.hex() == "6efbddaa1201"
    bg = signing.sign(TEST_KEY, wire.encode("BG"), 1, 0x0123456789AB, ARM)
    assert bg == head + mac
    assert bg.hex() == "4247" + "00" * 29 + "01" + "ab8967452301" + "6efbddaa1201"
    gb = signing.sign(TEST_KEY, wire.encode("GB"), 0, 0x0123456789AC, ARM)
    assert gb.hex().endswith("00" + "ac8967452301" + "3291c1d28978")
    assert signing.verify(TEST_KEY, bg, ARM) == (1, 0x0123456789AB)
    assert signing.verify(TEST_KEY, bg[:-1], ARM) is None
    altered = bytes([bg[0] ^ 1]) + bg[1:]
    assert signing.verify(TEST_KEY, altered, ARM) is None
    # For another controller, or any: forged.
    assert signing.verify(TEST_KEY, bg, ARM + 1) is None
    assert signing.verify(TEST_KEY, bg) is None
    # protocol/src/client/signed/key.rs: the tag of b"abc" for any controller (id 0).
    assert signing.tag(TEST_KEY, b"abc").hex() == "3961210c3c17"
    assert signing.tag(TEST_KEY, b"abc", ARM).hex() == "345451bf5251"


def test_controller_ids_derive_as_the_rust_side_derives_them() -> None:
    # protocol/src/client/signed/identity.rs: FNV-1a over the parts, each ended by a 0 byte.
    h = 0x811C9DC5
    for b in b"ranger-mk1\x00127.0.0.1:7031\x00":
        h = ((h ^ b) * 0x01000193) % 2**32
    assert h == ARM


def test_keys_are_32_bytes_a_hex_string_or_a_path_and_never_shown(tmp_path: Path) -> None:
    text = TEST_KEY.hex()
    assert signing.load_key(TEST_KEY) == TEST_KEY
    assert signing.load_key(text) == TEST_KEY
    assert signing.load_key(text.upper()) == TEST_KEY
    path = tmp_path / "k"
    path.write_text(text + "\n")
    path.chmod(0o600)
    assert signing.load_key(path) == TEST_KEY
    assert signing.load_key(str(path)) == TEST_KEY
    # Readable by others: refused with the chmod that fixes it.
    path.chmod(0o644)
    with pytest.raises(ValueError, match=f"chmod 600 {path}"):
        signing.load_key(path)
    # A wrong key never appears in the error, nor a signer's key in its repr.
    for wrong in [text[:-1] + "g", text[:-2]]:
        with pytest.raises((ValueError, OSError)) as error:
            signing.load_key(wrong)
        assert text[:16] not in str(error.value)
    signer = signing.Signer(text, link_id=2)
    assert text[:16] not in repr(signer) and "link 2" in repr(signer)


def test_timestamps_increase_and_answers_must_be_the_controllers_and_fresh() -> None:
    signer = signing.Signer(TEST_KEY, link_id=3, controller_id=ARM)
    first, t1 = signer.sign(wire.encode("PS"))
    _, t2 = signer.sign(wire.encode("PS"))
    assert t2 > t1 > 11 * 365 * 86_400 * 100_000
    assert first[31] == 3
    assert signing.verify(TEST_KEY, first, ARM) == (3, t1)
    answer = signing.sign(TEST_KEY, wire.encode("SP"), 0, t2, ARM)
    assert signer.open(answer, t2) == answer[:31]
    assert signer.open(answer, t2 + 1) is None
    assert signer.open(signing.sign(TEST_KEY, wire.encode("SP"), 3, t2, ARM), t2) is None
    assert signer.open(signing.sign(TEST_KEY, wire.encode("SP"), 0, t2, ARM + 1), t2) is None
    # Without the id: only an identity report opens, and names it.
    learner = signing.Signer(TEST_KEY, link_id=4)
    report = wire.encode("QS", [ARM >> 16, ARM & 0xFFFF], signing.IDENTITY_INDEX)
    assert learner.open(signing.sign(TEST_KEY, report, 0, t2, ARM), t2) == report
    assert learner.open(answer, t2) is None
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
    other.chmod(0o600)
    with armgate.Arm("127.0.0.1", sim.port, timeout=0.1, retries=0, joints=6, key=other) as wrong:
        with pytest.raises(armgate.ReplyTimeout, match="has it another key") as silence:
            wrong.get_tcp_pose()
    # With a key an unanswered request is re-sent for 2 s (a restart's reservation): 21 sends
    # 0.1 s apart, each a forgery here.
    forged = silence.value.attempts
    assert forged > signing.RESERVE_SECONDS / 0.1, forged
    with armgate.Arm("127.0.0.1", sim.port, key=key_file, link_id=9) as arm:
        counts = arm.request("SQ", index=4).values
        assert arm.controller_id is not None
    # Policy 1 (required), an unsigned and a forged (other key) datagram dropped.
    assert counts[0] == 1.0
    assert counts[3] == 1.0
    assert counts[5] == forged


def test_a_signed_client_says_when_the_controller_answers_unsigned(mk1, key_file: Path) -> None:  # type: ignore[no-untyped-def]
    with armgate.Arm("127.0.0.1", mk1.port, timeout=0.1, retries=0, joints=6, key=key_file) as arm:
        with pytest.raises(armgate.SignatureMismatch):
            arm.get_tcp_pose()


def test_two_arms_with_default_options_sign_on_distinct_links(sim_factory, key_file: Path) -> None:  # type: ignore[no-untyped-def]
    sim = sim_factory("ranger-mk1", "--key", str(key_file))
    with armgate.Arm("127.0.0.1", sim.port, key=key_file) as a, armgate.Arm(
        "127.0.0.1", sim.port, key=key_file
    ) as b:
        assert a.link_id != b.link_id
        assert a.controller_id == b.controller_id
        for _ in range(20):
            a.get_tcp_pose()
            b.get_tcp_pose()
        # Nothing dropped as replayed (SQ index 4, f6).
        assert a.request("SQ", index=4).values[6] == 0.0


def test_right_after_a_restart_the_client_resends_until_the_reservation_passes(
    sim_factory, key_file: Path, tmp_path: Path  # type: ignore[no-untyped-def]
) -> None:
    """docs/safety.md, "A restart refuses signed requests for up to 2 s": the same Arm, with the
    default timeout and retries (4 sends 0.2 s apart, less than the 2 s), is served by the
    simulator restarted mid-session with its replay state, as the Rust client is
    (tests/e2e_signing.rs, right_after_a_restart_the_client_resends_until_the_reservation_passes_and_is_served)."""
    port = free_port()
    args = ["--key", str(key_file), "--state", str(tmp_path / "replay"),
            "--controller-id", "5eed0003"]
    sim = sim_factory("ranger-mk1", *args, port=port)
    with armgate.Arm("127.0.0.1", port, key=key_file, link_id=1, joints=6) as arm:
        before = arm.get_tcp_pose()
        sim.stop()
        sim_factory("ranger-mk1", *args, port=port, ready=False)
        # Its first sends are dropped (not newer than the reservation kept before the
        # restart); it resends, signed anew, until they are newer.
        started = time.monotonic()
        after = arm.get_tcp_pose()
        waited = time.monotonic() - started
        counts = arm.request("SQ", index=4).values
    assert counts[6] >= 1.0, f"refused first: {counts}"
    assert waited > (armgate.DEFAULT_RETRIES + 1) * armgate.DEFAULT_TIMEOUT, waited
    assert waited < signing.RESERVE_SECONDS + 1.0, waited
    assert after.xyz == pytest.approx(before.xyz, abs=1e-6)
