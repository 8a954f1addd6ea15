"""The 31-byte datagram (docs/protocol.md) and how a reply is matched to its request.

A message is two ASCII command characters, seven float32 little-endian values f0..f6 and an
index byte. Replies carry the characters reversed (``BG`` -> ``GB``). Errors and warnings are
ASCII texts starting at byte 0 (``ER20 Cmd BG rejected``), NUL-terminated and zero-filled.

The protocol has no sequence numbers. A datagram answers a request if

* it is a normal reply whose characters are the request's reversed and, for the commands that
  echo their index, the index matches: the via slot (bits 0-6) for ``jV`` and ``VP``, the bank
  bit (bit 7) for ``jP`` and ``TM``, the whole index for ``SQ``; or
* it is an ``ER`` text that names the request's characters (``ER20 Cmd BG rejected``,
  ``ER00 Cmd XX not understood``, ``ER01 Msg XX undersized.``), or ``ER10`` for ``OF`` /
  ``ER11`` for ``ON``: the request was refused.

Every other ``ER``/``WN`` text is an unsolicited notice; every other normal reply is stale (the
late answer to an earlier, retried request). These are the Rust client's rules
(client/src/matching.rs); which request a text refuses is the grammar's (errors.py's
``refuses``, checked against protocol/grammar.json).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from typing import Optional, Sequence, Tuple

from .errors import ControllerMessage

MESSAGE_LEN = 31
"""Bytes in every datagram."""

VALUES = 7
"""Float values per message."""

BANK2 = 0x80
TOOL_FRAME = 0x01
"""Index bit of ``TW``: the twist is in the tool frame."""
"""Bit 7 of the index: bank 2 (joints 7..) for joint requests."""

THETA3 = 0x01
"""Index bit of ``KR``: f0 is θ3 (rad)."""
THETA5 = 0x02
"""Index bit of ``KR``: f1 is θ5 (rad; eight joints)."""
CHOSEN = 0x40
"""Index bit of ``KG`` and ``KS``: solve with this client's ``KR`` choice."""

_FLOATS = struct.Struct("<7f")


@dataclass(frozen=True)
class Message:
    """A decoded normal (non-text) message."""

    chars: str
    values: Tuple[float, ...]
    index: int


def encode(chars: str, values: Sequence[float] = (), index: int = 0) -> bytes:
    """The 31 bytes of a request: two characters, up to seven values (zero-padded), index."""
    if len(chars) != 2:
        raise ValueError(f"a command is two characters, not {chars!r}")
    if len(values) > VALUES:
        raise ValueError(f"{len(values)} values: a message carries {VALUES}")
    if not 0 <= index <= 0xFF:
        raise ValueError(f"index {index} does not fit a byte")
    padded = list(values) + [0.0] * (VALUES - len(values))
    return chars.encode("ascii") + _FLOATS.pack(*padded) + bytes([index])


def decode(datagram: bytes) -> Optional[Message]:
    """The message in ``datagram`` (its first 31 bytes), or None if it is too short."""
    if len(datagram) < MESSAGE_LEN:
        return None
    return Message(
        chars=datagram[:2].decode("latin-1"),
        values=_FLOATS.unpack_from(datagram, 2),
        index=datagram[30],
    )


def text_of(datagram: bytes) -> Optional[str]:
    """The ``ER``/``WN`` text in ``datagram`` (up to the first NUL), or None if it is no text."""
    if len(datagram) < MESSAGE_LEN or datagram[:2] not in (b"ER", b"WN"):
        return None
    body = datagram[:MESSAGE_LEN - 1].split(b"\0", 1)[0]
    return "".join(chr(b) if 0x20 <= b < 0x7F else "?" for b in body)


def reversed_chars(chars: str) -> str:
    """The characters of the reply to ``chars``."""
    return chars[::-1]


def _index_matches(chars: str, request: int, reply: int) -> bool:
    if chars in ("jV", "VP"):
        return request & ~BANK2 == reply & ~BANK2
    if chars in ("jP", "TM"):
        return request & BANK2 == reply & BANK2
    if chars in ("SQ", "TW", "jW", "jT", "VT", "KR"):
        return request == reply
    return True


def answers(chars: str, text: str) -> bool:
    """Whether the error ``text`` answers a request with characters ``chars``."""
    return text.startswith("ER") and ControllerMessage(text).refuses == chars


# What a received datagram is, relative to the request being waited for.
REPLY = "reply"
REJECTED = "rejected"
NOTICE = "notice"
OTHER = "other"


def classify(chars: str, index: int, datagram: bytes) -> Tuple[str, Optional[str]]:
    """``(kind, text)``: ``REPLY``, ``REJECTED`` (with the text), ``NOTICE`` (with the text) or
    ``OTHER`` (a stale reply or not a message at all)."""
    text = text_of(datagram)
    if text is not None:
        return (REJECTED if answers(chars, text) else NOTICE), text
    message = decode(datagram)
    if (
        message is not None
        and message.chars == reversed_chars(chars)
        and _index_matches(chars, index, message.index)
    ):
        return REPLY, None
    return OTHER, None
