"""Signed datagrams (docs/protocol.md, "Signed datagrams"; docs/safety.md, "Signing").

A signed datagram is the 31-byte message followed by a 13-byte block: the sender's link id
(1 byte; 0 is the controller's), a timestamp (48 bits little-endian, 10 us steps since
2015-01-01 UTC) and a tag, the first 6 bytes of HMAC-SHA256(key, bytes 0..37). The Rust side
is protocol/src/client/signed.
"""

from __future__ import annotations

import hashlib
import hmac
import os
import time
from typing import Optional, Tuple, Union

from . import wire

KEY_LEN = 32
SIGNATURE_LEN = 13
SIGNED_LEN = wire.MESSAGE_LEN + SIGNATURE_LEN
TAG_LEN = 6
CONTROLLER_LINK = 0
EPOCH_UNIX = 1_420_070_400
"""2015-01-01 00:00:00 UTC, the timestamps' epoch."""
TIMESTAMP_MAX = (1 << 48) - 1

KeyLike = Union[bytes, str, "os.PathLike[str]"]


def read_key(path: Union[str, "os.PathLike[str]"]) -> bytes:
    """The key in a key file: the first line that is neither empty nor a ``#`` comment, 64 hex
    digits."""
    with open(path, encoding="ascii") as f:
        for line in f:
            line = line.strip()
            if line and not line.startswith("#"):
                if len(line) != 2 * KEY_LEN:
                    raise ValueError(f"{path}: the key has {len(line)} characters, not 64")
                key = bytes.fromhex(line)
                if not any(key):
                    raise ValueError(f"{path}: the key is all zeros")
                return key
    raise ValueError(f"{path}: no key: expected 64 hex digits on one line")


def tag(key: bytes, signed: bytes) -> bytes:
    """The tag of ``signed`` (the message, link id and timestamp)."""
    return hmac.new(key, signed, hashlib.sha256).digest()[:TAG_LEN]


def sign(key: bytes, message: bytes, link: int, timestamp: int) -> bytes:
    """``message`` (31 bytes) signed on ``link`` at ``timestamp``."""
    head = message + bytes([link]) + (timestamp & TIMESTAMP_MAX).to_bytes(6, "little")
    return head + tag(key, head)


def verify(key: bytes, datagram: bytes) -> Optional[Tuple[int, int]]:
    """``(link, timestamp)`` of a signed datagram whose tag is ``key``'s, else None."""
    if len(datagram) < SIGNED_LEN:
        return None
    head, received = datagram[:38], datagram[38:SIGNED_LEN]
    if not hmac.compare_digest(tag(key, head), received):
        return None
    return datagram[31], int.from_bytes(datagram[32:38], "little")


class Signer:
    """A key, a link id (1..255) and the last timestamp used. Timestamps come from the wall
    clock (10 us since 2015) and always increase, also across restarts while the clock does
    not go back; clients that run at the same time need link ids of their own."""

    def __init__(self, key: KeyLike, link_id: int = 1) -> None:
        if isinstance(key, bytes):
            if len(key) != KEY_LEN:
                raise ValueError(f"a key is {KEY_LEN} bytes, not {len(key)}")
            self.key = key
        else:
            self.key = read_key(key)
        if not 1 <= link_id <= 255:
            raise ValueError(f"link id {link_id}: use 1..255 (0 is the controller's)")
        self.link_id = link_id
        self.last = 0

    def sign(self, message: bytes) -> Tuple[bytes, int]:
        """The signed datagram and its timestamp."""
        now = (time.time_ns() // 1000 - EPOCH_UNIX * 1_000_000) // 10
        self.last = max(now, self.last + 1)
        return sign(self.key, message, self.link_id, self.last), self.last

    def open(self, datagram: bytes, not_before: int) -> Optional[bytes]:
        """The message of a datagram from the controller if it is signed with the key on the
        controller's link and not older than ``not_before``; else None."""
        block = verify(self.key, datagram)
        if block is None or block[0] != CONTROLLER_LINK or block[1] < not_before:
            return None
        return datagram[: wire.MESSAGE_LEN]
