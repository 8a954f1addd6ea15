//! Signing on the client side (docs/safety.md, "Signing"): every request signed with the key,
//! its link id and a timestamp from the wall clock; every answer checked.
//!
//! The timestamp is the wall-clock time in 10 µs steps since 2015-01-01 UTC (MAVLink's), and
//! at least one more than the last one this client used: it increases across restarts of the
//! client as long as the computer's clock does not go back. Clients that run at the same time
//! need link ids of their own: the controller keeps one timestamp per link id.

use std::path::Path;
use std::time::{SystemTime, UNIX_EPOCH};

use armgate_protocol::client::MESSAGE_LEN;
use armgate_protocol::client::signed::{
    CONTROLLER_LINK, SIGNED_LEN, Signature, Signed, SigningKey, timestamp_from_unix_us,
};

use crate::ClientError;

/// The link id a client signs with unless told otherwise.
pub const DEFAULT_LINK: u8 = 1;

/// A key, a link id and the last timestamp used.
#[derive(Clone, Debug)]
pub struct Signer {
    key: SigningKey,
    link: u8,
    last: u64,
}

impl Signer {
    /// Signs with `key` on `link` (1..=255; 0 is the controller's).
    pub fn new(key: SigningKey, link: u8) -> Result<Self, ClientError> {
        if link == CONTROLLER_LINK {
            return Err(ClientError::InvalidArgument(
                "link id 0 is the controller's: use 1..=255".into(),
            ));
        }
        Ok(Self { key, link, last: 0 })
    }

    /// Reads the key file at `path` (64 hex digits on one line).
    pub fn from_file(path: &Path, link: u8) -> Result<Self, ClientError> {
        let text = std::fs::read_to_string(path).map_err(|e| {
            ClientError::InvalidArgument(format!("key file {}: {e}", path.display()))
        })?;
        let key = SigningKey::parse(&text).map_err(|e| {
            ClientError::InvalidArgument(format!("key file {}: {e}", path.display()))
        })?;
        Self::new(key, link)
    }

    /// The link id.
    pub fn link(&self) -> u8 {
        self.link
    }

    /// A signer with the same key on the next link id (255 is followed by 1): for a second
    /// socket of the same program (teleop's jog stream), whose requests would otherwise race
    /// the first one's timestamps on one link.
    pub fn next_link(&self) -> Self {
        Self {
            key: self.key.clone(),
            link: self.link % 255 + 1,
            last: 0,
        }
    }

    /// `message` signed with a new timestamp, and that timestamp.
    pub fn sign(&mut self, message: &[u8; MESSAGE_LEN]) -> ([u8; SIGNED_LEN], u64) {
        let now = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map(|d| u64::try_from(d.as_micros()).unwrap_or(u64::MAX))
            .unwrap_or(0);
        self.last = timestamp_from_unix_us(now).max(self.last.saturating_add(1));
        let signature = Signature {
            link: self.link,
            timestamp: self.last,
        };
        (signature.emit(message, &self.key), self.last)
    }

    /// The message of a datagram from the controller, if it is signed with the key on the
    /// controller's link and not older than `not_before` (the request it may answer): a
    /// forged, unsigned or replayed answer is `None`.
    pub fn open(&self, datagram: &[u8], not_before: u64) -> Option<[u8; MESSAGE_LEN]> {
        let signed = Signed::new_checked(datagram).ok()?;
        let signature = Signature::parse(&signed, &self.key).ok()?;
        if signature.link != CONTROLLER_LINK || signature.timestamp < not_before {
            return None;
        }
        let mut message = [0; MESSAGE_LEN];
        message
            .iter_mut()
            .zip(signed.message())
            .for_each(|(m, b)| *m = *b);
        Some(message)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const KEY: &str = "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f";

    fn key() -> SigningKey {
        SigningKey::parse(KEY).unwrap()
    }

    #[test]
    fn timestamps_come_from_the_clock_and_always_increase() {
        let mut signer = Signer::new(key(), 7).unwrap();
        let message = [0u8; MESSAGE_LEN];
        let (first, t1) = signer.sign(&message);
        let (_, t2) = signer.sign(&message);
        assert!(t2 > t1);
        // 2026 or later, in 10 µs since 2015.
        assert!(t1 > 11 * 365 * 86_400 * 100_000);
        let block = Signed::new_checked(&first[..]).unwrap();
        assert_eq!(block.link(), 7);
        assert_eq!(block.timestamp(), t1);
        assert!(Signer::new(key(), 0).is_err());
        assert_eq!(signer.next_link().link(), 8);
        assert_eq!(Signer::new(key(), 255).unwrap().next_link().link(), 1);
    }

    #[test]
    fn only_fresh_answers_signed_by_the_controller_open() {
        let signer = Signer::new(key(), 1).unwrap();
        let reply = [b'G'; MESSAGE_LEN];
        let by = |link, timestamp| Signature { link, timestamp }.emit(&reply, &key());
        assert_eq!(signer.open(&by(0, 100), 100), Some(reply));
        // Older than the request, on a client's link, unsigned, altered.
        assert_eq!(signer.open(&by(0, 99), 100), None);
        assert_eq!(signer.open(&by(1, 100), 100), None);
        assert_eq!(signer.open(&reply, 0), None);
        let mut altered = by(0, 100);
        altered[2] ^= 1;
        assert_eq!(signer.open(&altered, 100), None);
    }
}
