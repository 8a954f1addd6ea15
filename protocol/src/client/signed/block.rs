//! The signature block: its length-checked view ([`Signed`]) and its validated form
//! ([`Signature`]).

use core::fmt;

use super::{SIGNED_LEN, SigningKey, TAG_LEN, TIMESTAMP_MAX};
use crate::client::MESSAGE_LEN;

/// Byte offsets of the block's fields.
mod field {
    use core::ops::Range;

    pub const LINK: usize = 31;
    pub const TIMESTAMP: Range<usize> = 32..38;
    pub const TAG: Range<usize> = 38..44;
    /// What the tag covers: the message, the link id and the timestamp.
    pub const SIGNED: Range<usize> = 0..38;
}

/// Why a datagram is not a validly signed one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SignatureError {
    /// No block at all: the datagram is at most the 31-byte message.
    Unsigned,
    /// Longer than the message, shorter than a signed datagram: the block is cut off.
    Truncated,
    /// The tag is not the key's tag of the datagram (forged, altered, or another key).
    BadTag,
}

impl fmt::Display for SignatureError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Unsigned => "unsigned datagram",
            Self::Truncated => "signature block truncated",
            Self::BadTag => "signature does not match the key",
        })
    }
}

impl core::error::Error for SignatureError {}

/// A datagram of at least [`SIGNED_LEN`] bytes: the message and a signature block, not yet
/// verified. Only the first [`SIGNED_LEN`] bytes are read (as only 31 of an unsigned one).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Signed<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> Signed<T> {
    /// Wraps a datagram that has a whole block; says why not otherwise.
    pub fn new_checked(buffer: T) -> Result<Self, SignatureError> {
        match buffer.as_ref().len() {
            n if n <= MESSAGE_LEN => Err(SignatureError::Unsigned),
            n if n < SIGNED_LEN => Err(SignatureError::Truncated),
            _ => Ok(Self { buffer }),
        }
    }

    /// Bytes 0..31: the message.
    pub fn message(&self) -> &[u8] {
        self.bytes(0..MESSAGE_LEN)
    }

    /// Byte 31: the sender's link id.
    pub fn link(&self) -> u8 {
        self.buffer
            .as_ref()
            .get(field::LINK)
            .copied()
            .unwrap_or_default()
    }

    /// Bytes 32..38: the timestamp (48 bits, little-endian).
    pub fn timestamp(&self) -> u64 {
        let mut wide = [0u8; 8];
        wide.iter_mut()
            .zip(self.bytes(field::TIMESTAMP))
            .for_each(|(w, b)| *w = *b);
        u64::from_le_bytes(wide)
    }

    /// Bytes 38..44: the tag.
    pub fn tag(&self) -> [u8; TAG_LEN] {
        let mut tag = [0; TAG_LEN];
        tag.iter_mut()
            .zip(self.bytes(field::TAG))
            .for_each(|(t, b)| *t = *b);
        tag
    }

    fn bytes(&self, range: core::ops::Range<usize>) -> &[u8] {
        self.buffer.as_ref().get(range).unwrap_or_default()
    }
}

/// A verified signature block: who signed (the link id) and when (the timestamp).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Signature {
    /// The sender's link id ([`CONTROLLER_LINK`](super::CONTROLLER_LINK) for the controller).
    pub link: u8,
    /// 10 µs steps since 2015-01-01 UTC; only the low 48 bits go on the wire.
    pub timestamp: u64,
}

impl Signature {
    /// The block of `signed`, if its tag is `key`'s. (Whether the timestamp is new is the
    /// receiver's question.)
    pub fn parse<T: AsRef<[u8]>>(
        signed: &Signed<T>,
        key: &SigningKey,
    ) -> Result<Self, SignatureError> {
        if !key.verify(signed.bytes(field::SIGNED), &signed.tag()) {
            return Err(SignatureError::BadTag);
        }
        Ok(Self {
            link: signed.link(),
            timestamp: signed.timestamp(),
        })
    }

    /// `message` signed with this block under `key`.
    pub fn emit(&self, message: &[u8; MESSAGE_LEN], key: &SigningKey) -> [u8; SIGNED_LEN] {
        let mut out = [0u8; SIGNED_LEN];
        let timestamp = (self.timestamp & TIMESTAMP_MAX).to_le_bytes();
        // Copied as slices (a chain of byte iterators cost the controller's signing of every
        // answer about 400 instructions more, qemu-bench).
        if let Some(slot) = out.get_mut(..MESSAGE_LEN) {
            slot.copy_from_slice(message);
        }
        if let Some(slot) = out.get_mut(field::LINK) {
            *slot = self.link;
        }
        if let (Some(slot), Some(bytes)) = (
            out.get_mut(field::TIMESTAMP),
            timestamp.get(..field::TIMESTAMP.len()),
        ) {
            slot.copy_from_slice(bytes);
        }
        let tag = key.tag(out.get(field::SIGNED).unwrap_or_default());
        if let Some(slot) = out.get_mut(field::TAG) {
            slot.copy_from_slice(&tag);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::client::signed::ControllerId;
    use crate::client::signed::key::tests::TEST_KEY;

    /// `BG` signed on link 1 at timestamp 0x0123456789ab with the test key for controller
    /// 0xed0a5e0c. Python (python/tests/test_signing.py computes the same):
    /// `m = b"BG" + bytes(29) + bytes([1]) + (0x0123456789ab).to_bytes(6, "little")`,
    /// `c = (0xed0a5e0c).to_bytes(4, "little")`,
    /// `m + hmac.new(bytes(range(32)), c + m, hashlib.sha256).digest()[:6]`.
    const SIGNED_BG: &str =
        "4247000000000000000000000000000000000000000000000000000000000001ab89674523016efbddaa1201";
    /// Its reply `GB`, signed by the controller (link 0) one step later.
    const SIGNED_GB: &str =
        "4742000000000000000000000000000000000000000000000000000000000000ac89674523013291c1d28978";

    /// The test key for controller 0xed0a5e0c.
    fn arm_key() -> SigningKey {
        SigningKey::parse(TEST_KEY)
            .unwrap()
            .for_controller(ControllerId(0xed0a_5e0c))
    }

    fn hex(text: &str) -> [u8; SIGNED_LEN] {
        let mut out = [0; SIGNED_LEN];
        for (o, pair) in out.iter_mut().zip(text.as_bytes().chunks(2)) {
            *o = u8::from_str_radix(core::str::from_utf8(pair).unwrap(), 16).unwrap();
        }
        out
    }

    fn message(chars: &[u8; 2]) -> [u8; MESSAGE_LEN] {
        let mut m = [0; MESSAGE_LEN];
        m[..2].copy_from_slice(chars);
        m
    }

    #[test]
    fn emit_gives_the_known_bytes() {
        let key = arm_key();
        let bg = Signature {
            link: 1,
            timestamp: 0x0123_4567_89ab,
        };
        assert_eq!(bg.emit(&message(b"BG"), &key), hex(SIGNED_BG));
        let gb = Signature {
            link: 0,
            timestamp: 0x0123_4567_89ac,
        };
        assert_eq!(gb.emit(&message(b"GB"), &key), hex(SIGNED_GB));
        // Bits above the 48 are not sent.
        let wide = Signature {
            timestamp: bg.timestamp | 1 << 50,
            ..bg
        };
        assert_eq!(wide.emit(&message(b"BG"), &key), hex(SIGNED_BG));
    }

    #[test]
    fn parse_reads_the_fields_and_checks_the_tag() {
        let key = arm_key();
        let bytes = hex(SIGNED_BG);
        let signed = Signed::new_checked(&bytes[..]).unwrap();
        assert_eq!(signed.message(), &message(b"BG")[..]);
        assert_eq!(signed.link(), 1);
        assert_eq!(signed.timestamp(), 0x0123_4567_89ab);
        assert_eq!(signed.tag(), [0x6e, 0xfb, 0xdd, 0xaa, 0x12, 0x01]);
        assert_eq!(
            Signature::parse(&signed, &key),
            Ok(Signature {
                link: 1,
                timestamp: 0x0123_4567_89ab
            })
        );
        // Every byte is covered: a change anywhere is a bad tag.
        for k in 0..SIGNED_LEN {
            let mut altered = bytes;
            altered[k] ^= 0x01;
            let signed = Signed::new_checked(&altered[..]).unwrap();
            assert_eq!(
                Signature::parse(&signed, &key),
                Err(SignatureError::BadTag),
                "byte {k}"
            );
        }
        // Another key, or the same key for another controller (or for any).
        let other = SigningKey::parse(&TEST_KEY.replace("1f", "20"))
            .unwrap()
            .for_controller(key.controller());
        for other in [
            other,
            key.for_controller(ControllerId(0xed0a_5e0d)),
            key.for_controller(ControllerId::ANY),
        ] {
            assert_eq!(
                Signature::parse(&signed, &other),
                Err(SignatureError::BadTag)
            );
        }
    }

    #[test]
    fn lengths_tell_unsigned_truncated_and_signed_apart() {
        let bytes = hex(SIGNED_BG);
        for n in 0..=MESSAGE_LEN {
            assert_eq!(
                Signed::new_checked(&bytes[..n]),
                Err(SignatureError::Unsigned)
            );
        }
        for n in MESSAGE_LEN + 1..SIGNED_LEN {
            assert_eq!(
                Signed::new_checked(&bytes[..n]),
                Err(SignatureError::Truncated)
            );
        }
        // A longer datagram: the bytes past the block are not read.
        let mut long = [0u8; 50];
        long[..SIGNED_LEN].copy_from_slice(&bytes);
        long[SIGNED_LEN..].fill(0xff);
        let key = arm_key();
        let signed = Signed::new_checked(&long[..]).unwrap();
        assert!(Signature::parse(&signed, &key).is_ok());
    }
}
