"""IK configuration branches by name (docs/kinematics.md, "Named configurations").

A branch is three bits: 1 shoulder right (else left), 2 elbow down (else up), 4 wrist flip (else
no flip), as ``KS``, ``KG`` and ``SQ`` 5 carry them, taken from the geometry on every robot with a
closed form; on a 7–8 joint arm a configuration is its bits with the redundancy values (θ3, θ5),
and on hybrid (a prismatic base) the wrist bit does not apply (``KG`` with it: ``BadIndex``). ``NAMES`` is the Rust protocol's
``branch::NAMES``; python/tests/test_grammar.py checks it against protocol/grammar.json.
"""

from typing import List, Tuple, Union

#: ``SQ`` index of the present configuration (the Rust protocol's ``branch::BRANCH_INDEX``).
PRESENT_INDEX = 5

#: Each bit with its (name, short letter) when clear and when set.
NAMES: List[Tuple[int, Tuple[Tuple[str, str], Tuple[str, str]]]] = [
    (1, (("shoulder-left", "l"), ("shoulder-right", "r"))),
    (2, (("elbow-up", "u"), ("elbow-down", "d"))),
    (4, (("wrist-noflip", "n"), ("wrist-flip", "f"))),
]


def branch_name(bits: int) -> str:
    """The names of branch ``bits``: ``shoulder-left,elbow-up,wrist-noflip``."""
    return ",".join(states[1 if bits & bit else 0][0] for bit, states in NAMES)


def short_name(bits: int) -> str:
    """The short form of branch ``bits``: ``lun``."""
    return "".join(states[1 if bits & bit else 0][1] for bit, states in NAMES)


def parse_branch(branch: Union[int, str]) -> int:
    """The bits of a branch given by number (0..7), its three names (comma-separated, any
    order) or its short form (``lun``); ValueError otherwise, saying what a branch is."""
    refused = ValueError(
        f"{branch!r}: a branch is its three names, e.g. 'shoulder-left,elbow-up,wrist-noflip', "
        "short 'lun' (shoulder l/r, elbow u/d, wrist n/f), or its number 0 to 7 (1 shoulder "
        "right + 2 elbow down + 4 wrist flip); ik_solutions lists those with a solution"
    )
    if isinstance(branch, int) and not isinstance(branch, bool):
        if 0 <= branch <= 7:
            return branch
        raise refused
    text = str(branch)
    if text.isdigit():
        return parse_branch(int(text))
    words = [w.strip() for w in text.split(",")] if "," in text else list(text)
    if len(words) != len(NAMES):
        raise refused
    bits = 0
    for bit, states in NAMES:
        found = [i for i, (name, short) in enumerate(states) if name in words or short in words]
        if len(found) != 1:
            raise refused
        bits |= bit if found[0] == 1 else 0
    return bits
