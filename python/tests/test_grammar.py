"""errors.py against the grammar's table, protocol/grammar.json, which the Rust protocol crate
generates from its texts (its test fails when the file is stale): every code has its class, and
every form of text reads back with the same code, command, detail, refused request and
motion-ending flag as in Rust."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Dict, Tuple

import armgate
from armgate import errors, wire

TABLE = json.loads(
    (Path(__file__).resolve().parents[2] / "protocol" / "grammar.json").read_text()
)


def python_codes() -> Dict[Tuple[str, int], type]:
    """Every (prefix, code) errors.py gives a class of its own."""
    codes = {("ER", code): cls for code, cls in errors._ERRORS.items()}
    codes.update({("WN", code): cls for code, cls in errors._WARNINGS.items()})
    codes.update({("ER", code): armgate.DriveFault for code in range(30, 40)})
    return codes


def test_every_code_of_the_grammar_and_only_those_have_a_class() -> None:
    table = {(row["severity"], row["code"]): row for row in TABLE["codes"]}
    ours = python_codes()
    assert set(ours) == set(table)
    for key, row in table.items():
        assert (ours[key] is armgate.DriveFault) == row["drive_fault"], key


def test_every_form_reads_back_as_in_rust() -> None:
    ours = python_codes()
    for row in TABLE["texts"]:
        text = row["text"]
        e = armgate.ControllerMessage.from_text(text)
        key = (row["severity"], row["code"])
        if key in ours:
            assert type(e) is ours[key], text
        assert e.code == row["code"], text
        assert e.is_warning == (row["severity"] == "WN"), text
        assert e.command == row["command"], text
        assert e.detail == row["detail"], text
        assert e.refuses == row["refuses"], text
        assert e.ends_motion == row["ends_motion"], text
        for chars in {row["refuses"], row["command"], "OF", "ON", "BG"} - {None}:
            assert wire.answers(chars, text) == (chars == row["refuses"]), (text, chars)


def test_branch_names_are_the_protocols() -> None:
    from armgate import branch

    table = [
        (row["bit"], (tuple(row["clear"]), tuple(row["set"]))) for row in TABLE["branches"]
    ]
    assert branch.NAMES == table
    for bits in range(8):
        assert branch.parse_branch(branch.branch_name(bits)) == bits
        assert branch.parse_branch(branch.short_name(bits)) == bits
        assert branch.parse_branch(bits) == bits
        assert branch.parse_branch(str(bits)) == bits
    assert branch.branch_name(5) == "shoulder-right,elbow-up,wrist-flip"
    assert branch.parse_branch("wrist-noflip, elbow-down,shoulder-left") == 2
    for bad in (8, -1, "8", "lu", "lunf", "shoulder-left,elbow-up", "lrn", True):
        try:
            branch.parse_branch(bad)
        except ValueError as e:
            assert "a branch is its three names" in str(e)
        else:
            raise AssertionError(bad)


def test_the_signing_figures_are_the_protocols() -> None:
    from armgate import signing

    figures = TABLE["signing"]
    assert signing.TIMESTAMP_UNIT_US == figures["timestamp_unit_us"]
    assert signing.RESERVE_AHEAD == figures["reserve_ahead"]
    assert signing.RESERVE_SECONDS == 2.0


def test_obstacle_kinds_are_the_protocols() -> None:
    from armgate.status import OBSTACLE_KINDS, Nearest

    table = [(row["kind"], row["name"], row["short"]) for row in TABLE["obstacles"]]
    assert OBSTACLE_KINDS == table
    near = Nearest.from_values([0.0125, 5.0, 1.0, 2.0, 0.01, 0.0, 0.0])
    assert near == Nearest(gap=0.0125, link=5, obstacle="link", number=2, margin=0.01)
    assert near.pair == "L5 L2"
    assert Nearest.from_values([0.1, 6.0, 0.0, 1.0, 0.0, 0.0, 0.0]).pair == "L6 B1"
    assert Nearest.from_values([0.1, 6.0, 2.0, 0.0, 0.0, 0.0, 0.0]).pair == "L6 out"
    assert Nearest.from_values([0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0]) is None
