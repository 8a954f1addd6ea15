//! Signature checks: the first thing the cycle does with a datagram, before anything reads it.
//!
//! With a key ([`Signing::key`]), a request is served only if it carries a signature block
//! (`armgate_protocol::client::signed`) whose tag is the key's and whose timestamp is newer
//! than the last one served on its link id. Anything else is dropped and counted by cause
//! ([`SigningReport`], `SQ` index 4), never answered: an attacker learns nothing from the
//! controller's silence. The answers to a signed request, and the notices that follow it, are
//! signed with the controller's link id ([`CONTROLLER_LINK`]) and a timestamp no older than
//! any request served. Without a key every datagram is served unsigned, as the seed's were.
//!
//! The replay table is keyed by link id alone: a source address proves nothing, so a captured
//! datagram sent again from another address is still a replay. One slot per possible link id
//! (256), so no link is ever evicted (an evicted link would accept its old datagrams again).

use core::fmt;
use core::str::FromStr;

use crate::command::Class;
use armgate_protocol::client::signed::{
    CONTROLLER_LINK, SIGNED_LEN, Signature, SignatureError, Signed, SigningKey, SigningPolicy,
    SigningReport, TIMESTAMP_MAX,
};
use armgate_protocol::client::{Command, MESSAGE_LEN};

/// What an unsigned datagram may do while a key is set.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum UnsignedAccess {
    /// Nothing: it is dropped (the default).
    #[default]
    Refused,
    /// Read (what the session answers to everyone, [`Class::Read`]: pose, joints,
    /// temperatures, status, IK solutions) and stop ([`Class::Stop`], `ST`, `jR`: the arm
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
    /// The shared key, if any.
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
}

/// A datagram let through: the message to handle, and whether its answers are signed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Admitted<'a> {
    pub message: &'a [u8],
    pub signed: bool,
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
    replay: Replay,
    /// Whether the last datagram served was signed (its sender gets the notices).
    last_signed: bool,
    report: SigningReport,
}

impl Gate {
    pub fn new(signing: Signing) -> Self {
        let report = SigningReport {
            policy: Some(signing.policy()),
            ..SigningReport::default()
        };
        Self {
            signing,
            replay: Replay {
                floors: [0; 256],
                clock: 0,
            },
            last_signed: false,
            report,
        }
    }

    /// The counters and the policy.
    pub fn report(&self) -> SigningReport {
        self.report
    }

    /// Whether the last datagram served was signed.
    pub fn last_signed(&self) -> bool {
        self.last_signed
    }

    /// `datagram` if it may be served; `None` (counted) if it is dropped.
    pub fn admit<'a>(&mut self, datagram: &'a [u8]) -> Option<Admitted<'a>> {
        let report = &mut self.report;
        let admitted = match &self.signing.key {
            None => Some(Admitted {
                message: datagram,
                signed: false,
            }),
            Some(key) => match Signed::new_checked(datagram) {
                Ok(signed) => verify(key, &signed, datagram, &mut self.replay, report),
                Err(SignatureError::Truncated) => {
                    bump(&mut report.dropped_truncated);
                    None
                }
                Err(_) => unsigned(self.signing.unsigned, datagram, report),
            },
        };
        let admitted = admitted?;
        bump(if admitted.signed {
            &mut report.signed
        } else {
            &mut report.unsigned
        });
        self.last_signed = admitted.signed;
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

/// The timestamps: per link the lowest one still new, and the controller's own.
#[derive(Clone, Debug)]
struct Replay {
    /// Per link id, the last timestamp served + 1 (0: none yet).
    floors: [u64; 256],
    /// The controller's timestamp: the last it signed with, raised to every request served.
    clock: u64,
}

impl Replay {
    /// Serves `signature` if its timestamp is new on its link.
    fn accept(&mut self, signature: Signature) -> bool {
        let Some(floor) = self.floors.get_mut(usize::from(signature.link)) else {
            return false;
        };
        if signature.timestamp < *floor {
            return false;
        }
        *floor = signature.timestamp.saturating_add(1);
        // Answers are never older than a request served, so a client can refuse old ones.
        self.clock = self.clock.max(signature.timestamp.saturating_sub(1));
        true
    }

    /// The timestamp of the controller's next signature.
    fn tick_clock(&mut self) -> u64 {
        self.clock = self.clock.saturating_add(1).min(TIMESTAMP_MAX);
        self.clock
    }
}

/// A signed datagram, served if its tag is `key`'s, its link a client's and its timestamp new.
fn verify<'a>(
    key: &SigningKey,
    signed: &Signed<&'a [u8]>,
    datagram: &'a [u8],
    replay: &mut Replay,
    report: &mut SigningReport,
) -> Option<Admitted<'a>> {
    let signature = match Signature::parse(signed, key) {
        Ok(s) if s.link != CONTROLLER_LINK => s,
        _ => {
            bump(&mut report.dropped_forged);
            return None;
        }
    };
    if !replay.accept(signature) {
        bump(&mut report.dropped_replayed);
        return None;
    }
    Some(Admitted {
        message: datagram.get(..MESSAGE_LEN).unwrap_or_default(),
        signed: true,
    })
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
            let chars = [0, 1].map(|i| datagram.get(i).copied().unwrap_or_default());
            Command::from_chars(chars).is_some_and(|c| Class::of(c) != Class::Command)
        }
        UnsignedAccess::All => true,
    };
    if !allowed {
        bump(&mut report.dropped_unsigned);
        return None;
    }
    Some(Admitted {
        message: datagram,
        signed: false,
    })
}

/// Adds one to `counter`, saturating.
fn bump(counter: &mut u32) {
    *counter = counter.saturating_add(1);
}
