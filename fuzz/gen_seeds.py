#!/usr/bin/env python3
"""Writes the seed corpus of the `datagram` fuzz target to seeds/datagram/.

Input format (see fuzz_targets/datagram.rs): chunks of one header byte (bits 0-1: ticks after
it, 0/1/8/64; bit 2 clear: a datagram; bits 3-7: its length) followed by the datagram. (Bit 2
set makes a chunk a CAN frame, or with bits 3-6 all set a signed datagram: a control byte and
the 31-byte message, which the target signs.) The poses are the
ranger-mk1 home pose (drives' home angles) and small moves from it.
"""
import os
import struct

HOME_XYZ = (0.0, 0.02, 0.666)
HOME_RPY = (0.0, 0.0, -1.5707963)
HOME_Q = (1.5708, 0.0, 1.5708, 0.0, 1.5708, 0.0)
TICKS = {0: 0, 1: 1, 8: 2, 64: 3}


def dgram(cmd, values=(), index=0):
    v = list(values) + [0.0] * (7 - len(values))
    return cmd.encode() + struct.pack("<7f", *v) + bytes([index])


def chunk(data, ticks=0):
    assert len(data) <= 31
    return bytes([(len(data) << 3) | TICKS[ticks]]) + data


def signed(data, control=1, ticks=0):
    """A signed-datagram chunk: control byte bits 0-2 the link id, 3-5 the timestamp step
    (+ 0..7 - 2 over the link's last), bit 6 a forged tag, bit 7 a cut-off block."""
    assert len(data) == 31
    return bytes([0b1111_100 | TICKS[ticks]]) + bytes([control]) + data


def moved(xyz, dx=0.0, dy=0.0, dz=0.0):
    return (xyz[0] + dx, xyz[1] + dy, xyz[2] + dz)


def joints(dq=None):
    q = list(HOME_Q)
    for i, d in (dq or {}).items():
        q[i] += d
    return q


SEEDS = {
    # Single datagrams.
    "cm2": chunk(dgram("CM", [2.0]), 1),
    "gt": chunk(dgram("GT", [*moved(HOME_XYZ, dz=0.002), *HOME_RPY, 0.5])),
    "gl": chunk(dgram("GL", [*moved(HOME_XYZ, dz=0.002), 0.0, 0.0, -0.7071068, 0.7071068])),
    "bg": chunk(dgram("BG"), 8),
    "vp": chunk(dgram("VP", [*moved(HOME_XYZ, dx=0.002), *HOME_RPY, 0.0], 0)),
    "ve": chunk(dgram("VE"), 8),
    "jg": chunk(dgram("jG", joints({0: 0.01}))),
    "jb": chunk(dgram("jB"), 8),
    "ps": chunk(dgram("PS")),
    "tm": chunk(dgram("TM")),
    "rc": chunk(dgram("RC", joints({0: 0.001}))),
    "undersized": chunk(b"BG", 1),
    "unknown": chunk(dgram("XX")),
    # Sequences that run motions.
    "cart_move": chunk(dgram("CM", [2.0]), 1)
    + chunk(dgram("GT", [*moved(HOME_XYZ, dz=0.002), *HOME_RPY, 0.5]))
    + chunk(dgram("BG"), 64)
    + chunk(dgram("PS"), 64)
    + chunk(dgram("BG"), 1),
    "cart_via": chunk(dgram("CM", [2.0]), 1)
    + chunk(dgram("VP", [*moved(HOME_XYZ, dx=0.002), *HOME_RPY, 0.0], 0))
    + chunk(dgram("VP", [*moved(HOME_XYZ, dx=0.002, dz=0.002), *HOME_RPY, 0.0], 1))
    + chunk(dgram("VP", [*HOME_XYZ, *HOME_RPY, 0.0], 2))
    + chunk(dgram("VE"), 64)
    + chunk(dgram("PS"), 64)
    + chunk(dgram("VC"), 1),
    "joint_move": chunk(dgram("CM", [1.0]), 1)
    + chunk(dgram("jG", joints({0: 0.01, 2: -0.01})))
    + chunk(dgram("jB"), 64)
    + chunk(dgram("jP"), 1)
    + chunk(dgram("jR"), 1),
    "joint_via": chunk(dgram("CM", [1.0]), 1)
    + chunk(dgram("jV", [*joints({3: 0.01}), 0.1], 0))
    + chunk(dgram("jV", [*joints({3: 0.02}), 0.1], 1))
    + chunk(dgram("jV", [*joints({3: 0.0}), 0.1], 2))
    + chunk(dgram("jE"), 64)
    + chunk(dgram("jP"), 64)
    + chunk(dgram("jC"), 1),
    "drives": chunk(dgram("OF"), 1)
    + chunk(dgram("OF"))
    + chunk(dgram("ON"), 1)
    + chunk(dgram("ON"))
    + chunk(dgram("RC", joints({0: 0.001})), 1)
    + chunk(dgram("jP"))
    + chunk(dgram("TM"))
    + chunk(dgram("ST"), 1),
    # KR (ranger-mk1 has no redundancy parameters: refused), KS and KG asking for its choice.
    "ik_redundancy": chunk(dgram("CM", [1.0]), 1)
    + chunk(dgram("KR", [0.5, 0.2], 3))
    + chunk(dgram("KS", [*HOME_XYZ, *HOME_RPY], 0x40))
    + chunk(dgram("KG", [*moved(HOME_XYZ, dz=0.002), *HOME_RPY, 1.0], 0x48), 64)
    + chunk(dgram("ST"), 1),
    # Signed: a move with a replay of its BG (step 2 - 2 = 0: the same timestamp), a forged tag,
    # a cut-off block and the controller's own link 0 among the fresh datagrams.
    "signed_move": signed(dgram("CM", [2.0]), 0b011_001, 1)
    + signed(dgram("GT", [*moved(HOME_XYZ, dz=0.002), *HOME_RPY, 0.5]), 0b011_001)
    + signed(dgram("BG"), 0b011_001, 8)
    + signed(dgram("BG"), 0b010_001, 1)
    + signed(dgram("ST"), 0b0100_0000 | 0b011_001, 1)
    + signed(dgram("ST"), 0b1000_0000 | 0b011_010, 1)
    + signed(dgram("PS"), 0b011_000, 1)
    + signed(dgram("PS"), 0b011_010, 64),
}

# Inputs that fail a check of the target in some configuration (see README.md, "Findings").
FINDINGS = {
    # RC (mode 0) declares joint 5 to be 0 rad, below its 0.785 rad limit; it is accepted. CM 1
    # and one tick: the joint command for joint 5 is 0.003888 rad (0 + max_rate * period), still
    # outside the limits. Fails only with ARMGATE_FUZZ_STRICT_LIMITS=1.
    "rc-outside-joint-limits": chunk(dgram("RC", joints({4: -1.5708})))
    + chunk(dgram("CM", [1.0]), 1),
}

here = os.path.dirname(os.path.abspath(__file__))
for kind, inputs in (("seeds", SEEDS), ("findings", FINDINGS)):
    out = os.path.join(here, kind, "datagram")
    os.makedirs(out, exist_ok=True)
    for name, data in inputs.items():
        with open(os.path.join(out, name), "wb") as f:
            f.write(data)
    print(f"{len(inputs)} {kind} in {out}")
