//! The shared key: 32 bytes, written in a key file as 64 hex digits on one line.

use core::fmt;

use hmac::{Hmac, Mac};
use sha2::Sha256;

use super::{ControllerId, TAG_LEN};

/// The length of a key in bytes.
pub const KEY_LEN: usize = 32;

/// A signing key for one controller, with HMAC-SHA256's inner and outer states computed once
/// when it is made, so that one tag costs two SHA-256 compressions (the controller id and the
/// signed part, 4 + 38 bytes, and the outer hash each fit one block).
#[derive(Clone)]
pub struct SigningKey {
    mac: Hmac<Sha256>,
    /// The controller the tags are for (covered by every tag, never sent).
    controller: ControllerId,
}

/// Why a text is not a key.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum KeyError {
    /// No line that is neither empty nor a `#` comment.
    Missing,
    /// The line has a character that is not a hex digit.
    NotHex,
    /// The line has this many hex digits, not 64.
    WrongLength(usize),
    /// Every byte is zero: a placeholder, not a key.
    AllZero,
}

impl fmt::Display for KeyError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Missing => f.write_str("no key: expected 64 hex digits on one line"),
            Self::NotHex => f.write_str("the key is not hex digits"),
            Self::WrongLength(n) => write!(f, "the key has {n} hex digits, not 64"),
            Self::AllZero => f.write_str("the key is all zeros"),
        }
    }
}

impl core::error::Error for KeyError {}

impl SigningKey {
    /// The key of these bytes, for [`ControllerId::ANY`] until
    /// [`for_controller`](Self::for_controller) names one.
    pub fn new(bytes: &[u8; KEY_LEN]) -> Self {
        // HMAC pads a key shorter than the hash's 64-byte block with zeros: padded here, the
        // block-sized constructor cannot fail (`new_from_slice` could, in its signature).
        let mut block = [0u8; 64];
        block.iter_mut().zip(bytes).for_each(|(b, k)| *b = *k);
        Self {
            mac: <Hmac<Sha256> as Mac>::new(&block.into()),
            controller: ControllerId::ANY,
        }
    }

    /// The same key, its tags for `controller`: a datagram signed for one controller is
    /// forged to every other one that has the key.
    pub fn for_controller(&self, controller: ControllerId) -> Self {
        Self {
            mac: self.mac.clone(),
            controller,
        }
    }

    /// The controller the tags are for.
    pub fn controller(&self) -> ControllerId {
        self.controller
    }

    /// Reads a key file (see [`parse_key`]).
    pub fn parse(text: &str) -> Result<Self, KeyError> {
        parse_key(text).map(|bytes| Self::new(&bytes))
    }

    /// The tag of `signed`: the first [`TAG_LEN`] bytes of HMAC-SHA256 over the controller id
    /// (4 bytes, little-endian) and `signed`.
    pub fn tag(&self, signed: &[u8]) -> [u8; TAG_LEN] {
        let mut mac = self.mac.clone();
        mac.update(&self.controller.to_bytes());
        mac.update(signed);
        let full = mac.finalize().into_bytes();
        let mut tag = [0; TAG_LEN];
        tag.iter_mut().zip(full.iter()).for_each(|(t, b)| *t = *b);
        tag
    }

    /// True if `tag` is the tag of `signed` (compared in constant time).
    pub fn verify(&self, signed: &[u8], tag: &[u8; TAG_LEN]) -> bool {
        let mut mac = self.mac.clone();
        mac.update(&self.controller.to_bytes());
        mac.update(signed);
        mac.verify_truncated_left(tag).is_ok()
    }
}

/// The key bytes of a key file: the first line that is neither empty nor a comment (`#`), 64
/// hex digits (either case), spaces around them ignored.
pub fn parse_key(text: &str) -> Result<[u8; KEY_LEN], KeyError> {
    let line = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))
        .ok_or(KeyError::Missing)?;
    if line.len() != 2 * KEY_LEN {
        return Err(if line.bytes().all(|b| b.is_ascii_hexdigit()) {
            KeyError::WrongLength(line.len())
        } else {
            KeyError::NotHex
        });
    }
    let mut bytes = [0u8; KEY_LEN];
    for (byte, pair) in bytes.iter_mut().zip(line.as_bytes().chunks_exact(2)) {
        let digit = |c: &u8| char::from(*c).to_digit(16).ok_or(KeyError::NotHex);
        let (Some(hi), Some(lo)) = (pair.first(), pair.get(1)) else {
            return Err(KeyError::NotHex);
        };
        // Two hex digits make at most 255.
        *byte = u8::try_from(digit(hi)? * 16 + digit(lo)?).unwrap_or(u8::MAX);
    }
    if bytes == [0; KEY_LEN] {
        return Err(KeyError::AllZero);
    }
    Ok(bytes)
}

impl fmt::Debug for SigningKey {
    /// Never shows the key.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "SigningKey(.., controller {})", self.controller)
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// The key of the known-answer tests: bytes 0x00, 0x01, .., 0x1f.
    pub(in super::super) const TEST_KEY: &str =
        "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f";

    #[test]
    fn the_tag_is_hmac_sha256_over_the_controller_id_and_the_bytes_truncated_to_6_bytes() {
        // Python: hmac.new(bytes(range(32)), bytes(4) + b"abc", hashlib.sha256).hexdigest()
        // starts 3961210c3c17; with the id 0xed0a5e0c (0c 5e 0a ed) before b"abc", 345451bf5251.
        let key = SigningKey::parse(TEST_KEY).unwrap();
        let tag = key.tag(b"abc");
        assert_eq!(tag, ABC_TAG);
        assert!(key.verify(b"abc", &ABC_TAG));
        let mut wrong = ABC_TAG;
        wrong[5] ^= 1;
        assert!(!key.verify(b"abc", &wrong));
        assert!(!key.verify(b"abd", &ABC_TAG));
        let arm = key.for_controller(ControllerId(0xed0a_5e0c));
        assert_eq!(arm.controller(), ControllerId(0xed0a_5e0c));
        assert_eq!(arm.tag(b"abc"), [0x34, 0x54, 0x51, 0xbf, 0x52, 0x51]);
        assert!(!arm.verify(b"abc", &ABC_TAG), "another controller's tag");
        assert!(
            arm.for_controller(ControllerId::ANY)
                .verify(b"abc", &ABC_TAG)
        );
    }

    const ABC_TAG: [u8; TAG_LEN] = [0x39, 0x61, 0x21, 0x0c, 0x3c, 0x17];

    #[test]
    fn key_files_are_64_hex_digits_on_one_line() {
        let file = format!("# lab arm, 2026\n\n  {}  \n", TEST_KEY.to_uppercase());
        let key = SigningKey::parse(&file).unwrap();
        assert_eq!(key.tag(b"abc"), ABC_TAG);
        assert_eq!(SigningKey::parse("").unwrap_err(), KeyError::Missing);
        assert_eq!(
            SigningKey::parse("# only\n").unwrap_err(),
            KeyError::Missing
        );
        assert_eq!(
            SigningKey::parse("0011").unwrap_err(),
            KeyError::WrongLength(4)
        );
        let not_hex = TEST_KEY.replace('a', "g");
        assert_eq!(SigningKey::parse(&not_hex).unwrap_err(), KeyError::NotHex);
        assert_eq!(
            SigningKey::parse(&"0".repeat(64)).unwrap_err(),
            KeyError::AllZero
        );
        assert_eq!(format!("{key:?}"), "SigningKey(.., controller 00000000)");
    }
}
