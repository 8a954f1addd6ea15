//! Signed datagrams: the 31-byte message followed by a 13-byte signature block, so that only
//! holders of the shared key can command the arm (docs/protocol.md, "Signed datagrams").
//!
//! | Bytes | Content                                                                    |
//! |-------|----------------------------------------------------------------------------|
//! | 0–30  | the message, as unsigned (command, f0..f6, index; or a text)               |
//! | 31    | link id: the sender's (1..=255 for clients; 0 is the controller's own)     |
//! | 32–37 | timestamp, 48 bits little-endian, units of 10 µs since 2015-01-01 UTC      |
//! | 38–43 | tag: the first 6 bytes of HMAC-SHA256(key, controller id ‖ bytes 0–37)     |
//!
//! The controller id (4 bytes little-endian, [`ControllerId`]) is covered by the tag but not
//! sent: a datagram signed for one arm is forged to every other arm that has the key.
//! The design is MAVLink 2's message signing, with three changes: the tag is an HMAC (MAVLink
//! hashes `key || data` with plain SHA-256), the controller signs with the link id 0 that no
//! client may use (so a reply reflected back to the controller is refused), and the receiver
//! keys its replay check by link id alone (a source address proves nothing).
//!
//! * [`Signed`]: the length-checked view of a signed datagram.
//! * [`Signature`]: the validated block (link id and timestamp), `parse`d against a key and
//!   `emit`ted with one.
//! * [`SigningKey`]: the 32-byte key with its HMAC states computed once.
//! * [`SigningReport`]: the signing counters, the reply to `SQ` index 4.
//! * [`ControllerId`], [`IdentityReport`]: who the controller is, the reply to `SQ` index 6.

mod block;
mod identity;
mod key;
#[cfg(feature = "std")]
mod key_file;
mod link_identity;
mod report;
mod timestamp;

pub use block::{Signature, SignatureError, Signed};
pub use identity::{BadControllerId, ControllerId, IDENTITY_INDEX, IdentityReport};
pub use key::{KEY_LEN, KeyError, SigningKey, parse_key};
#[cfg(feature = "std")]
pub use key_file::read_key_file;
pub use link_identity::{link_identity, link_of_identity};
pub use report::{SIGNING_INDEX, SigningPolicy, SigningReport};
pub use timestamp::{
    TIMESTAMP_EPOCH_UNIX, TIMESTAMP_MAX, TIMESTAMP_UNIT_US, timestamp_from_unix_us,
};

/// The length of the signature block.
pub const SIGNATURE_LEN: usize = 13;
/// The length of a signed datagram: the 31-byte message and the block.
pub const SIGNED_LEN: usize = super::MESSAGE_LEN + SIGNATURE_LEN;
/// The length of the tag (48 bits of the HMAC).
pub const TAG_LEN: usize = 6;
/// The link id the controller signs with; a request on it is refused.
pub const CONTROLLER_LINK: u8 = 0;
/// How far ahead of a served timestamp the controller's kept replay reservation goes (2 s in
/// 10 µs steps): one store write per 2 s of use at most, and after a restart signed requests
/// other than stops are refused until the clients' clocks pass it, for up to this long (the
/// controller's `cycle::replay`; clients resend for this long).
pub const RESERVE_AHEAD: u64 = 200_000;
