//! Signature checks: the first thing the cycle does with a datagram, before anything reads it.
//!
//! With a key ([`Signing::key`], for this controller's id), a request is served only if it
//! carries a signature block (`armgate_protocol::client::signed`) whose tag is the key's for
//! this controller and whose timestamp is new (module `replay`: newer than the last one served
//! on its link id, within a minute of the newest on any link for a link's first, newer than
//! anything served before a restart). A validly signed stop (`ST`, `jR`) is served even when
//! not new: a replayed stop only stops. `SQ` index 6 signed for [`ControllerId::ANY`] is
//! served too: it tells a client the id to sign for. Anything else is dropped and counted by cause
//! ([`SigningReport`], `SQ` index 4), never answered: an attacker learns nothing from the
//! controller's silence. The answers to a signed request, and the notices that follow it, are
//! signed with the controller's link id ([`CONTROLLER_LINK`]) and a timestamp no older than
//! any request served. Without a key every datagram is served unsigned, as the seed's were.
//!
//! The replay table is keyed by link id alone: a source address proves nothing, so a captured
//! datagram sent again from another address is still a replay.

use core::fmt;
use core::str::FromStr;

use super::budget::Work;
use super::replay::{Freshness, Replay, ReplayStore};
use crate::command::Class;
use armgate_protocol::client::signed::{
    CONTROLLER_LINK, ControllerId, IDENTITY_INDEX, SIGNED_LEN, Signature, SignatureError, Signed,
    SigningKey, SigningPolicy, SigningReport,
};
use armgate_protocol::client::{Command, MESSAGE_LEN};

/// What an unsigned datagram may do while a key is set.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum UnsignedAccess {
    /// Nothing: it is dropped (the default).
    #[default]
    Refused,
    /// Read (what the session answers to everyone, [`Class::Read`]: pose, joints,
    /// temperatures, status; not the IK solutions, which plan) and stop ([`Class::Stop`], `ST`, `jR`: the arm
    /// holds, the principle that any client can stop it); anything else is dropped.
    Read,
    /// Everything: the key then only signs the answers to signed clients (a lab moving its
    /// clients to signing one by one).
    All,
}

impl FromStr for UnsignedAccess {
    type Err = UnknownAccess;

    /// `no`, `read` or `all`.
    fn from_str(s: &str) -> Result<Self, UnknownAccess> {
        match s.trim() {
            "no" => Ok(Self::Refused),
            "read" => Ok(Self::Read),
            "all" => Ok(Self::All),
            _ => Err(UnknownAccess),
        }
    }
}

impl fmt::Display for UnsignedAccess {
    /// `no`, `read` or `all`, as [`FromStr`] takes them.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Refused => "no",
            Self::Read => "read",
            Self::All => "all",
        })
    }
}

/// The text is not `no`, `read` or `all`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct UnknownAccess;

impl fmt::Display for UnknownAccess {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("expected no, read or all")
    }
}

#[cfg(feature = "std")]
impl std::error::Error for UnknownAccess {}

/// A cycle's signing settings (none by default: everything unsigned, as the seed).
#[derive(Clone, Debug, Default)]
pub struct Signing {
    /// The shared key, if any, for this controller's id
    /// ([`SigningKey::for_controller`]; docs/protocol.md says how the shells choose it).
    pub key: Option<SigningKey>,
    /// What unsigned datagrams may do while a key is set.
    pub unsigned: UnsignedAccess,
}

impl Signing {
    /// The policy `SQ` index 4 reports.
    pub fn policy(&self) -> SigningPolicy {
        match (&self.key, self.unsigned) {
            (None, _) => SigningPolicy::Off,
            (Some(_), UnsignedAccess::Refused) => SigningPolicy::Required,
            (Some(_), UnsignedAccess::Read) => SigningPolicy::UnsignedRead,
            (Some(_), UnsignedAccess::All) => SigningPolicy::UnsignedAll,
        }
    }

    /// The controller id the tags are for ([`ControllerId::ANY`] without a key).
    pub fn controller(&self) -> ControllerId {
        self.key
            .as_ref()
            .map_or(ControllerId::ANY, SigningKey::controller)
    }
}

/// A datagram let through: the message to handle, and its link id if it came signed (its
/// answers are then signed).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Admitted<'a> {
    pub message: &'a [u8],
    pub link: Option<u8>,
}

/// An answer ready to send: the 31-byte message, signed or not.
#[derive(Clone, Copy, Debug)]
pub(super) struct Sealed {
    bytes: [u8; SIGNED_LEN],
    len: usize,
}

impl Sealed {
    /// The bytes to send.
    pub fn bytes(&self) -> &[u8] {
        self.bytes.get(..self.len).unwrap_or_default()
    }
}

/// The checks and their state: the key, the replay table, the counters.
#[derive(Clone, Debug)]
pub(super) struct Gate {
    signing: Signing,
    /// The key for [`ControllerId::ANY`]: the identity request's.
    any: Option<SigningKey>,
    replay: Replay,
    report: SigningReport,
}

impl Gate {
    /// The gate of `signing`, after a start whose store kept the reservation `reserved`.
    pub fn new(signing: Signing, reserved: u64) -> Self {
        let report = SigningReport {
            policy: Some(signing.policy()),
            ..SigningReport::default()
        };
        let any = signing
            .key
            .as_ref()
            .map(|k| k.for_controller(ControllerId::ANY));
        Self {
            signing,
            any,
            replay: Replay::new(reserved),
            report,
        }
    }

    /// The controller's id (`SQ` index 6).
    pub fn controller(&self) -> ControllerId {
        self.signing.controller()
    }

    /// Reservations the replay store could not keep.
    pub fn store_failures(&self) -> u32 {
        self.replay.store_failures
    }

    /// The counters and the policy.
    pub fn report(&self) -> SigningReport {
        self.report
    }

    /// `datagram` if it may be served; `None` (counted) if it is dropped. `store` keeps the
    /// replay reservation across restarts.
    pub fn admit<'a>(
        &mut self,
        datagram: &'a [u8],
        store: &mut impl ReplayStore,
    ) -> Option<Admitted<'a>> {
        let report = &mut self.report;
        let admitted = match (&self.signing.key, &self.any) {
            (Some(key), Some(any)) => match Signed::new_checked(datagram) {
                Ok(signed) => {
                    let keys = Keys { key, any };
                    verify(keys, &signed, datagram, (&mut self.replay, store), report)
                }
                Err(SignatureError::Truncated) => {
                    bump(&mut report.dropped_truncated);
                    None
                }
                Err(_) => unsigned(self.signing.unsigned, datagram, report),
            },
            _ => Some(Admitted {
                message: datagram,
                link: None,
            }),
        };
        let admitted = admitted?;
        bump(if admitted.link.is_some() {
            &mut report.signed
        } else {
            &mut report.unsigned
        });
        Some(admitted)
    }

    /// `message` as it goes to a client: signed if `signed` (and a key is set).
    pub fn seal(&mut self, message: &[u8; MESSAGE_LEN], signed: bool) -> Sealed {
        match (&self.signing.key, signed) {
            (Some(key), true) => {
                let signature = Signature {
                    link: CONTROLLER_LINK,
                    timestamp: self.replay.tick_clock(),
                };
                Sealed {
                    bytes: signature.emit(message, key),
                    len: SIGNED_LEN,
                }
            }
            _ => {
                let mut bytes = [0; SIGNED_LEN];
                bytes.iter_mut().zip(message).for_each(|(b, m)| *b = *m);
                Sealed {
                    bytes,
                    len: MESSAGE_LEN,
                }
            }
        }
    }
}

/// The key for this controller, and for any (the identity request's).
#[derive(Clone, Copy)]
struct Keys<'k> {
    key: &'k SigningKey,
    any: &'k SigningKey,
}

/// A signed datagram, served if its tag is the key's for this controller (or for any, on an
/// identity request), its link a client's and its timestamp new, or if it is a stop.
fn verify<'a>(
    keys: Keys<'_>,
    signed: &Signed<&'a [u8]>,
    datagram: &'a [u8],
    (replay, store): (&mut Replay, &mut impl ReplayStore),
    report: &mut SigningReport,
) -> Option<Admitted<'a>> {
    let chars = [0, 1].map(|i| datagram.get(i).copied().unwrap_or_default());
    let command = Command::from_chars(chars);
    let parsed = Signature::parse(signed, keys.key).or_else(|e| {
        // Only an identity request may be for any controller: it only reads the id.
        if is_identity_request(datagram) {
            Signature::parse(signed, keys.any)
        } else {
            Err(e)
        }
    });
    let signature = match parsed {
        Ok(s) if s.link != CONTROLLER_LINK => s,
        _ => {
            bump(&mut report.dropped_forged);
            return None;
        }
    };
    // A stop that is not new is served all the same (it only stops) and moves nothing on.
    let stop = command.is_some_and(|c| Class::of(c) == Class::Stop);
    if replay.accept(signature, store) == Freshness::Old && !stop {
        bump(&mut report.dropped_replayed);
        return None;
    }
    Some(Admitted {
        message: datagram.get(..MESSAGE_LEN).unwrap_or_default(),
        link: Some(signature.link),
    })
}

/// True if `message` is `SQ` index 6, the identity request.
pub(super) fn is_identity_request(message: &[u8]) -> bool {
    message.get(..2) == Some(&Command::Status.chars()[..])
        && message.get(MESSAGE_LEN - 1) == Some(&IDENTITY_INDEX)
}

/// An unsigned datagram while a key is set, served as `access` allows.
fn unsigned<'a>(
    access: UnsignedAccess,
    datagram: &'a [u8],
    report: &mut SigningReport,
) -> Option<Admitted<'a>> {
    let allowed = match access {
        UnsignedAccess::Refused => false,
        UnsignedAccess::Read => {
            // Reads and stops, but none that plans (KS): the planning slot is the signed
            // clients' (module `budget`).
            let chars = [0, 1].map(|i| datagram.get(i).copied().unwrap_or_default());
            Command::from_chars(chars).is_some_and(|c| Class::of(c) != Class::Command)
                && !matches!(Work::of(datagram), Work::Plans(_))
        }
        UnsignedAccess::All => true,
    };
    if !allowed {
        bump(&mut report.dropped_unsigned);
        return None;
    }
    Some(Admitted {
        message: datagram,
        link: None,
    })
}

/// Adds one to `counter`, saturating.
fn bump(counter: &mut u32) {
    *counter = counter.saturating_add(1);
}
