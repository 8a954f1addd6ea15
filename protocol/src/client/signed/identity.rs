//! The controller's identity: a 32-bit id every tag covers (so a key shared by two arms moves
//! only the one addressed), and the `QS` reply to `SQ` index 6 that tells a client which arm it
//! talks to (docs/protocol.md, "Signed datagrams").

use core::fmt;

use crate::client::status::whole;
use crate::client::{Command, DecodeError, Reply};

/// `SQ` index of the identity report.
pub const IDENTITY_INDEX: u8 = 6;

/// A controller's id. [`ControllerId::ANY`] (0) is no controller's: a request signed for it is
/// served only if it is `SQ` index 6, so that a client can learn the id it must sign for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ControllerId(pub u32);

impl ControllerId {
    /// The wildcard: the id a client signs its identity request with before it knows the id.
    pub const ANY: Self = Self(0);

    /// The default id of a controller, from the texts that set it apart from other controllers
    /// on the same network (the robot file's name, the address it listens on): FNV-1a (32 bits)
    /// over them, each followed by a 0 byte; never [`ANY`](Self::ANY).
    pub fn derive(parts: &[&str]) -> Self {
        let mut hash: u32 = 0x811c_9dc5;
        for part in parts {
            for byte in part.bytes().chain([0]) {
                hash = (hash ^ u32::from(byte)).wrapping_mul(0x0100_0193);
            }
        }
        Self(hash.max(1))
    }

    /// The bytes the tag covers before the datagram's 38 (little-endian).
    pub fn to_bytes(self) -> [u8; 4] {
        self.0.to_le_bytes()
    }
}

impl fmt::Display for ControllerId {
    /// Eight hex digits, as the options take them (`--controller-id 1a2b3c4d`).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:08x}", self.0)
    }
}

/// The text is not 1 to 8 hex digits, or is 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BadControllerId;

impl fmt::Display for BadControllerId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a controller id is 1 to 8 hex digits, not 0")
    }
}

impl core::error::Error for BadControllerId {}

impl core::str::FromStr for ControllerId {
    type Err = BadControllerId;

    /// 1 to 8 hex digits (an optional `0x` before them), not 0.
    fn from_str(s: &str) -> Result<Self, BadControllerId> {
        let s = s.trim();
        let digits = s.strip_prefix("0x").unwrap_or(s);
        if digits.is_empty() || digits.len() > 8 {
            return Err(BadControllerId);
        }
        match u32::from_str_radix(digits, 16) {
            Ok(0) | Err(_) => Err(BadControllerId),
            Ok(id) => Ok(Self(id)),
        }
    }
}

/// The `QS` reply to `SQ` index 6: who the controller is, and what it saw of link ids shared by
/// two clients.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct IdentityReport {
    /// f0, f1: the id, its high and low 16 bits (each exact in an f32).
    pub controller: ControllerId,
    /// f2: signed datagrams that came on a link id from another source address than the
    /// link's last, within a second of it: two clients on one link id.
    pub shared_links: u32,
    /// f3: the last link id seen shared (0: none).
    pub last_shared: u8,
    /// f4: a link id no client was heard on lately, set aside for the asking client (0: none):
    /// clients that start at the same time get different ones.
    pub free_link: u8,
}

impl IdentityReport {
    /// The reply, index 6.
    pub fn to_reply(&self) -> Reply {
        let id = self.controller.0;
        Reply {
            command: Command::Status,
            values: [
                (id >> 16) as f32,
                (id & 0xffff) as f32,
                self.shared_links as f32,
                f32::from(self.last_shared),
                f32::from(self.free_link),
                0.0,
                0.0,
            ],
            index: IDENTITY_INDEX,
        }
    }

    /// Decodes a `QS` index-6 reply.
    pub fn from_reply(reply: &Reply) -> Result<Self, DecodeError> {
        if reply.command != Command::Status || reply.index != IDENTITY_INDEX {
            return Err(DecodeError::WrongCommand);
        }
        let [high, low, shared, last, free, ..] = reply.values.map(whole);
        let report = || -> Option<Self> {
            let (high, low) = (
                high.filter(|h| *h <= 0xffff)?,
                low.filter(|l| *l <= 0xffff)?,
            );
            Some(Self {
                controller: ControllerId(high << 16 | low),
                shared_links: shared?,
                last_shared: u8::try_from(last?).ok()?,
                free_link: u8::try_from(free?).ok()?,
            })
        };
        report().ok_or(DecodeError::BadField)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::client::{Message, Request};

    #[test]
    fn ids_are_derived_parsed_and_shown_as_hex() {
        // Python: h = 0x811c9dc5; for b in b"ranger-mk1\x00127.0.0.1:7031\x00":
        //   h = ((h ^ b) * 0x01000193) % 2**32
        let id = ControllerId::derive(&["ranger-mk1", "127.0.0.1:7031"]);
        assert_eq!(id, ControllerId(0xed0a_5e0c));
        assert_ne!(id, ControllerId::derive(&["ranger-mk1", "127.0.0.1:7032"]));
        assert_ne!(id, ControllerId::derive(&["ranger-mk11", "27.0.0.1:7031"]));
        assert_eq!(id.to_string(), "ed0a5e0c");
        assert_eq!("ed0a5e0c".parse(), Ok(id));
        assert_eq!("0xED0A5E0C".parse(), Ok(id));
        assert_eq!("7".parse(), Ok(ControllerId(7)));
        for bad in ["", "0", "0x", "123456789", "xyz", "-1"] {
            assert_eq!(bad.parse::<ControllerId>(), Err(BadControllerId), "{bad}");
        }
    }

    #[test]
    fn the_report_carries_the_id_in_two_halves_at_index_6() {
        let report = IdentityReport {
            controller: ControllerId(0xed0a_5e0c),
            shared_links: 3,
            last_shared: 1,
            free_link: 101,
        };
        let reply = report.to_reply();
        assert_eq!(reply.values[..5], [60682.0, 24076.0, 3.0, 1.0, 101.0]);
        let bytes = reply.to_bytes();
        let parsed = Reply::parse(&Message::new_checked(&bytes[..]).unwrap()).unwrap();
        assert_eq!(IdentityReport::from_reply(&parsed), Ok(report));
        let mut bad = reply;
        bad.values[1] = 65536.0;
        assert_eq!(IdentityReport::from_reply(&bad), Err(DecodeError::BadField));
        // The request is an ordinary SQ.
        let sq = Request {
            command: Command::Status,
            values: [0.0; 7],
            index: IDENTITY_INDEX,
        };
        assert_eq!(sq.to_bytes()[30], 6);
    }
}
