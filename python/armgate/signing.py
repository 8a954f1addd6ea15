"""Signed datagrams (docs/protocol.md, "Signed datagrams"; docs/safety.md, "Signing").

A signed datagram is the 31-byte message followed by a 13-byte block: the sender's link id
(1 byte; 0 is the controller's), a timestamp (48 bits little-endian, 10 us steps since
2015-01-01 UTC) and a tag, the first 6 bytes of HMAC-SHA256(key, controller id (4 bytes
little-endian) + bytes 0..37). The controller id is not sent: a datagram signed for one arm is
forged to every other arm with the key. A client that does not know the id signs ``SQ`` index 6
for id 0 (any controller) and takes the id the signed answer names. The Rust side is
protocol/src/client/signed.
"""

from __future__ import annotations

import hashlib
import hmac
import os
import secrets
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
TIMESTAMP_UNIT_US = 10
"""The timestamps' step (us)."""
RESERVE_AHEAD = 200_000
"""How far ahead of a served timestamp (in timestamp steps: 2 s) the controller keeps its replay
reservation: after a restart it drops signed requests other than stops for up to this long, so a
client with a key resends for at least this long (docs/safety.md). Both figures are the Rust
protocol's (``signed::RESERVE_AHEAD``, ``TIMESTAMP_UNIT_US``); python/tests/test_grammar.py
checks them against protocol/grammar.json."""
RESERVE_SECONDS = RESERVE_AHEAD * TIMESTAMP_UNIT_US / 1e6
""":data:`RESERVE_AHEAD` in seconds."""

ANY_CONTROLLER = 0
"""The controller id of a request for any controller: only ``SQ`` index 6 is served so."""
IDENTITY_INDEX = 6

KeyLike = Union[bytes, str, "os.PathLike[str]"]


def _key_line(line: str, where: str) -> bytes:
    """The key of one line of 64 hex digits; errors name ``where``, never the digits."""
    if len(line) != 2 * KEY_LEN:
        raise ValueError(f"{where}: the key has {len(line)} characters, not 64 hex digits")
    try:
        key = bytes.fromhex(line)
    except ValueError:
        raise ValueError(f"{where}: the key is not hex digits") from None
    if not any(key):
        raise ValueError(f"{where}: the key is all zeros")
    return key


def read_key(path: Union[str, "os.PathLike[str]"]) -> bytes:
    """The key in a key file: the first line that is neither empty nor a ``#`` comment, 64 hex
    digits. A file that group or others may read is refused (as ssh refuses such a private key),
    with the ``chmod`` that fixes it."""
    mode = os.stat(path).st_mode
    if os.name == "posix" and mode & 0o077:
        raise ValueError(
            f"{path}: the key file may be read by others (mode {mode & 0o777:o}): "
            f"chmod 600 {path}"
        )
    with open(path, encoding="ascii") as f:
        for line in f:
            line = line.strip()
            if line and not line.startswith("#"):
                return _key_line(line, str(path))
    raise ValueError(f"{path}: no key: expected 64 hex digits on one line")


def load_key(key: KeyLike) -> bytes:
    """The key of 32 bytes, of a string of 64 hex digits, or of the path of a key file (a
    string that is not 64 hex digits is a path). Errors never show the key."""
    if isinstance(key, (bytes, bytearray)):
        if len(key) != KEY_LEN:
            raise ValueError(f"a key is {KEY_LEN} bytes, not {len(key)}")
        return bytes(key)
    if isinstance(key, str) and len(key.strip()) == 2 * KEY_LEN and all(
        c in "0123456789abcdefABCDEF" for c in key.strip()
    ):
        return _key_line(key.strip(), "key")
    if isinstance(key, str) and len(key) >= KEY_LEN and all(c.isalnum() for c in key):
        # Not a key, and no file name either: most likely a mistyped key; never echo it.
        if not os.path.exists(key):
            raise ValueError("key: neither 64 hex digits nor an existing key file") from None
    return read_key(key)


def tag(key: bytes, signed: bytes, controller: int = ANY_CONTROLLER) -> bytes:
    """The tag of ``signed`` (the message, link id and timestamp) for ``controller``."""
    covered = controller.to_bytes(4, "little") + signed
    return hmac.new(key, covered, hashlib.sha256).digest()[:TAG_LEN]


def sign(
    key: bytes, message: bytes, link: int, timestamp: int, controller: int = ANY_CONTROLLER
) -> bytes:
    """``message`` (31 bytes) signed on ``link`` at ``timestamp`` for ``controller``."""
    head = message + bytes([link]) + (timestamp & TIMESTAMP_MAX).to_bytes(6, "little")
    return head + tag(key, head, controller)


def verify(
    key: bytes, datagram: bytes, controller: int = ANY_CONTROLLER
) -> Optional[Tuple[int, int]]:
    """``(link, timestamp)`` of a signed datagram whose tag is ``key``'s for ``controller``,
    else None."""
    if len(datagram) < SIGNED_LEN:
        return None
    head, received = datagram[:38], datagram[38:SIGNED_LEN]
    if not hmac.compare_digest(tag(key, head, controller), received):
        return None
    return datagram[31], int.from_bytes(datagram[32:38], "little")


def identity_of(message: bytes) -> Optional[int]:
    """The controller id a ``QS`` index-6 message names (f0: high 16 bits, f1: low), else
    None."""
    decoded = wire.decode(message)
    if decoded is None or decoded.chars != "QS" or decoded.index != IDENTITY_INDEX:
        return None
    high, low = decoded.values[0], decoded.values[1]
    if not all(v == int(v) and 0 <= v <= 0xFFFF for v in (high, low)):
        return None
    return int(high) << 16 | int(low)


class Signer:
    """A key, a link id (1..255; None: the one the controller sets aside for this client, a
    random one until then), the controller's id (None: learnt from its identity report) and the
    last timestamp used. Timestamps come from the wall clock (10 us since 2015) and always
    increase, also across restarts while the clock does not go back; clients that run at the
    same time need link ids of their own."""

    def __init__(
        self,
        key: KeyLike,
        link_id: Optional[int] = None,
        controller_id: Optional[int] = None,
    ) -> None:
        self._key = load_key(key)
        if link_id is not None and not 1 <= link_id <= 255:
            raise ValueError(f"link id {link_id}: use 1..255 (0 is the controller's)")
        if controller_id is not None and not 1 <= controller_id <= 0xFFFFFFFF:
            raise ValueError(f"controller id {controller_id}: use 1..0xffffffff")
        self.link_assigned = link_id is not None
        self.link_id = link_id if link_id is not None else secrets.randbelow(255) + 1
        self.controller_id = controller_id
        self.last = 0

    @property
    def needs_identity(self) -> bool:
        """True until the controller's id and the link id are known."""
        return self.controller_id is None or not self.link_assigned

    def identified(self, controller_id: int, free_link: int) -> None:
        """Takes the identity report's controller id, and the link set aside for this client
        unless one was given (0: none, the random one stays)."""
        self.controller_id = controller_id
        if not self.link_assigned:
            if free_link:
                self.link_id = free_link
            self.link_assigned = True

    def __repr__(self) -> str:
        # Never the key.
        controller = "unknown" if self.controller_id is None else f"{self.controller_id:08x}"
        return f"Signer(link {self.link_id}, controller {controller})"

    def sign(self, message: bytes) -> Tuple[bytes, int]:
        """The signed datagram and its timestamp (for any controller while the id is
        unknown)."""
        now = (time.time_ns() // 1000 - EPOCH_UNIX * 1_000_000) // TIMESTAMP_UNIT_US
        self.last = max(now, self.last + 1)
        controller = self.controller_id or ANY_CONTROLLER
        return sign(self._key, message, self.link_id, self.last, controller), self.last

    def open(self, datagram: bytes, not_before: int) -> Optional[bytes]:
        """The message of a datagram from the controller if it is signed with the key for this
        controller on the controller's link and not older than ``not_before``; else None. While
        the id is unknown, only an identity report opens, checked for the id it names."""
        controller = self.controller_id
        if controller is None:
            controller = identity_of(datagram[: wire.MESSAGE_LEN])
            if controller is None:
                return None
        block = verify(self._key, datagram, controller)
        if block is None or block[0] != CONTROLLER_LINK or block[1] < not_before:
            return None
        return datagram[: wire.MESSAGE_LEN]
