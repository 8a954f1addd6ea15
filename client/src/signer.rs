//! Signing on the client side (docs/safety.md, "Signing"): every request signed with the key,
//! its link id and a timestamp from the wall clock; every answer checked.
//!
//! The timestamp is the wall-clock time in 10 µs steps since 2015-01-01 UTC (MAVLink's), and
//! at least one more than the last one this client used: it increases across restarts of the
//! client as long as the computer's clock does not go back. Clients that run at the same time
//! need link ids of their own: the controller keeps one timestamp per link id. Unless told one
//! (`--link-id`), a client takes the link id the controller sets aside for it in its identity
//! report (a free one: clients that start together get different ones), asking on a random
//! link id first.
//!
//! Every tag covers the controller's id ([`ControllerId`]): a signer made without one learns it
//! from the controller's first signed answer, the identity report (`SQ` index 6), which the
//! controller serves signed for any controller.

use std::path::Path;
use std::time::{SystemTime, UNIX_EPOCH};

use armgate_protocol::client::signed::{
    CONTROLLER_LINK, ControllerId, IdentityReport, SIGNED_LEN, Signature, Signed, SigningKey,
    read_key_file, timestamp_from_unix_us,
};
use armgate_protocol::client::{MESSAGE_LEN, Message, Reply};

use crate::ClientError;

/// Where a signer's link id comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum LinkSource {
    /// Given (`--link-id`).
    Given,
    /// Set aside by the controller for this client.
    Assigned,
    /// Not yet: a random one, until the controller sets one aside.
    Unassigned,
}

/// A key, a link id and the last timestamp used.
#[derive(Clone, Debug)]
pub struct Signer {
    key: SigningKey,
    link: u8,
    source: LinkSource,
    last: u64,
}

impl Signer {
    /// Signs with `key` on `link` (1..=255; 0 is the controller's), or with `None` on the link
    /// the controller sets aside for this client (a random one until then).
    pub fn new(key: SigningKey, link: Option<u8>) -> Result<Self, ClientError> {
        let (link, source) = match link {
            Some(CONTROLLER_LINK) => {
                return Err(ClientError::InvalidArgument(
                    "link id 0 is the controller's: use 1..=255".into(),
                ));
            }
            Some(link) => (link, LinkSource::Given),
            None => (random_link(), LinkSource::Unassigned),
        };
        Ok(Self {
            key,
            link,
            source,
            last: 0,
        })
    }

    /// Reads the key file at `path` (64 hex digits on one line; refused if group or others may
    /// read it).
    pub fn from_file(path: &Path, link: Option<u8>) -> Result<Self, ClientError> {
        let key = read_key_file(path)
            .map_err(|e| ClientError::InvalidArgument(format!("key file {e}")))?;
        Self::new(key, link)
    }

    /// The link id.
    pub fn link(&self) -> u8 {
        self.link
    }

    /// The controller the signatures are for ([`ControllerId::ANY`]: not known yet).
    pub fn controller(&self) -> ControllerId {
        self.key.controller()
    }

    /// Signs for `controller` from now on.
    pub fn set_controller(&mut self, controller: ControllerId) {
        self.key = self.key.for_controller(controller);
    }

    /// True until the controller and the link id are known: the next request asks the
    /// controller's identity report first.
    pub fn needs_identity(&self) -> bool {
        self.controller() == ControllerId::ANY || self.source == LinkSource::Unassigned
    }

    /// Takes what the identity report says: the controller's id, and the link set aside for
    /// this client unless one was given (0: none set aside, the random one stays).
    pub fn identified(&mut self, report: &IdentityReport) {
        self.set_controller(report.controller);
        if self.source == LinkSource::Unassigned {
            if report.free_link != CONTROLLER_LINK {
                self.link = report.free_link;
            }
            self.source = LinkSource::Assigned;
        }
    }

    /// A signer with the same key on another link id: for a second socket of the same program
    /// (teleop's jog stream), whose requests would otherwise race the first one's timestamps
    /// on one link. The next one (255 is followed by 1) after a given link id; else one the
    /// controller sets aside.
    pub fn next_link(&self) -> Self {
        let (link, source) = match self.source {
            LinkSource::Given => (self.link % 255 + 1, LinkSource::Given),
            _ => (random_link(), LinkSource::Unassigned),
        };
        Self {
            key: self.key.clone(),
            link,
            source,
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
    /// Before the controller is known, only its identity report opens, checked with the key
    /// for the id it names.
    pub fn open(&self, datagram: &[u8], not_before: u64) -> Option<[u8; MESSAGE_LEN]> {
        let signed = Signed::new_checked(datagram).ok()?;
        let key = match self.controller() {
            ControllerId::ANY => {
                let message = Message::new_checked(signed.message()).ok()?;
                let reply = Reply::parse(&message).ok()?;
                let named = IdentityReport::from_reply(&reply).ok()?.controller;
                self.key.for_controller(named)
            }
            _ => self.key.clone(),
        };
        let signature = Signature::parse(&signed, &key).ok()?;
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

/// A random link id, 1..=255 (the standard library's per-process random hash keys, and the
/// clock).
fn random_link() -> u8 {
    use std::hash::BuildHasher;
    let seed = (SystemTime::now(), std::process::id());
    let random = std::collections::hash_map::RandomState::new().hash_one(seed);
    u8::try_from(random % 255).unwrap_or(0) + 1
}

#[cfg(test)]
mod tests {
    use super::*;

    const KEY: &str = "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f";

    const ARM: ControllerId = ControllerId(0x1234_5678);

    fn key() -> SigningKey {
        SigningKey::parse(KEY).unwrap().for_controller(ARM)
    }

    #[test]
    fn timestamps_come_from_the_clock_and_always_increase() {
        let mut signer = Signer::new(key(), Some(7)).unwrap();
        let message = [0u8; MESSAGE_LEN];
        let (first, t1) = signer.sign(&message);
        let (_, t2) = signer.sign(&message);
        assert!(t2 > t1);
        // 2026 or later, in 10 µs since 2015.
        assert!(t1 > 11 * 365 * 86_400 * 100_000);
        let block = Signed::new_checked(&first[..]).unwrap();
        assert_eq!(block.link(), 7);
        assert_eq!(block.timestamp(), t1);
        assert!(Signer::new(key(), Some(0)).is_err());
        assert_eq!(signer.next_link().link(), 8);
        assert_eq!(Signer::new(key(), Some(255)).unwrap().next_link().link(), 1);
        assert!(!signer.needs_identity());
    }

    #[test]
    fn only_fresh_answers_signed_by_the_controller_open() {
        let signer = Signer::new(key(), Some(1)).unwrap();
        assert_eq!(signer.controller(), ARM);
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
        // Signed for another controller.
        let other = Signature {
            link: 0,
            timestamp: 100,
        }
        .emit(&reply, &key().for_controller(ControllerId(7)));
        assert_eq!(signer.open(&other, 100), None);
    }

    #[test]
    fn a_signer_without_the_id_learns_it_from_the_identity_report_only() {
        let mut signer = Signer::new(key().for_controller(ControllerId::ANY), None).unwrap();
        assert!(signer.needs_identity());
        assert!((1..=255).contains(&signer.link()));
        let report = IdentityReport {
            controller: ARM,
            free_link: 101,
            ..IdentityReport::default()
        };
        let identity = report.to_reply().to_bytes();
        let by = |message: &[u8; MESSAGE_LEN], key: &SigningKey| {
            Signature {
                link: 0,
                timestamp: 100,
            }
            .emit(message, key)
        };
        assert_eq!(signer.open(&by(&identity, &key()), 100), Some(identity));
        // Another reply, or the report signed for another id than it names: not opened.
        assert_eq!(signer.open(&by(&[b'G'; MESSAGE_LEN], &key()), 100), None);
        let lying = by(&identity, &key().for_controller(ControllerId(9)));
        assert_eq!(signer.open(&lying, 100), None);
        signer.identified(&report);
        assert_eq!((signer.controller(), signer.link()), (ARM, 101));
        assert!(!signer.needs_identity());
        // Its second socket asks for a link of its own; a given link stays.
        assert!(signer.next_link().needs_identity());
        let mut given = Signer::new(key(), Some(9)).unwrap();
        given.identified(&report);
        assert_eq!(given.link(), 9);
        assert_eq!(
            signer.open(&by(&[b'G'; MESSAGE_LEN], &key()), 100),
            Some([b'G'; MESSAGE_LEN])
        );
    }
}
