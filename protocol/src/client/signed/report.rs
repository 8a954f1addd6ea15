//! The signing counters: the `QS` reply to `SQ` index 4 (docs/protocol.md).

use crate::client::status::whole;
use crate::client::{Command, DecodeError, Reply};

/// `SQ` index of the signing report.
pub const SIGNING_INDEX: u8 = 4;

/// What the controller does with datagrams (`QS` index 4, f0).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SigningPolicy {
    /// No key: every datagram is unsigned and served, as the seed's controller did.
    Off = 0,
    /// A key: only signed datagrams are served.
    Required = 1,
    /// A key, and unsigned datagrams may read (and stop) but not command.
    UnsignedRead = 2,
    /// A key, and unsigned datagrams may do everything (a lab's transition).
    UnsignedAll = 3,
}

impl SigningPolicy {
    /// Every policy, by code.
    pub const ALL: [Self; 4] = [
        Self::Off,
        Self::Required,
        Self::UnsignedRead,
        Self::UnsignedAll,
    ];
}

/// The `QS` reply to `SQ` index 4: what was served and what was dropped, by cause, since the
/// controller started. Dropped datagrams are never answered; this is where they show.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SigningReport {
    /// f0: the policy (`None` decodes nothing: [`SigningPolicy::Off`] is the default).
    pub policy: Option<SigningPolicy>,
    /// f1: signed datagrams served.
    pub signed: u32,
    /// f2: unsigned datagrams served.
    pub unsigned: u32,
    /// f3: unsigned datagrams dropped (a key is set, or they may only read).
    pub dropped_unsigned: u32,
    /// f4: datagrams with a cut-off signature block, dropped.
    pub dropped_truncated: u32,
    /// f5: datagrams whose tag is wrong (forged, altered, another key, or the controller's own
    /// link id), dropped.
    pub dropped_forged: u32,
    /// f6: datagrams whose timestamp is not newer than the last one served on their link
    /// (replayed, or a client clock gone back), dropped.
    pub dropped_replayed: u32,
}

impl SigningReport {
    /// The reply, index 4. (Counts above 2²⁴ are rounded by f32; they are for people.)
    pub fn to_reply(&self) -> Reply {
        let policy = self.policy.unwrap_or(SigningPolicy::Off);
        Reply {
            command: Command::Status,
            values: [
                f32::from(policy as u8),
                self.signed as f32,
                self.unsigned as f32,
                self.dropped_unsigned as f32,
                self.dropped_truncated as f32,
                self.dropped_forged as f32,
                self.dropped_replayed as f32,
            ],
            index: SIGNING_INDEX,
        }
    }

    /// Decodes a `QS` index-4 reply.
    pub fn from_reply(reply: &Reply) -> Result<Self, DecodeError> {
        if reply.command != Command::Status || reply.index != SIGNING_INDEX {
            return Err(DecodeError::WrongCommand);
        }
        let [policy, signed, unsigned, du, dt, df, dr] = reply.values.map(whole);
        let report = || -> Option<Self> {
            let policy = SigningPolicy::ALL
                .into_iter()
                .find(|p| Some(*p as u32) == policy)?;
            Some(Self {
                policy: Some(policy),
                signed: signed?,
                unsigned: unsigned?,
                dropped_unsigned: du?,
                dropped_truncated: dt?,
                dropped_forged: df?,
                dropped_replayed: dr?,
            })
        };
        report().ok_or(DecodeError::BadField)
    }

    /// Every datagram dropped.
    pub fn dropped(&self) -> u32 {
        [
            self.dropped_unsigned,
            self.dropped_truncated,
            self.dropped_forged,
            self.dropped_replayed,
        ]
        .into_iter()
        .fold(0, u32::saturating_add)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::client::{MESSAGE_LEN, Message};

    #[test]
    fn the_report_is_seven_counts_at_index_4() {
        let report = SigningReport {
            policy: Some(SigningPolicy::UnsignedRead),
            signed: 12,
            unsigned: 3,
            dropped_unsigned: 1,
            dropped_truncated: 2,
            dropped_forged: 5,
            dropped_replayed: 7,
        };
        let bytes = report.to_reply().to_bytes();
        let mut expected = [0u8; MESSAGE_LEN];
        expected[..2].copy_from_slice(b"QS");
        // 2.0 = 00 00 00 40, 12.0 = 00 00 40 41, 3.0 = 00 00 40 40, 1.0 = 00 00 80 3f, ...
        let values: [[u8; 4]; 7] = [
            [0, 0, 0, 0x40],
            [0, 0, 0x40, 0x41],
            [0, 0, 0x40, 0x40],
            [0, 0, 0x80, 0x3f],
            [0, 0, 0, 0x40],
            [0, 0, 0xa0, 0x40],
            [0, 0, 0xe0, 0x40],
        ];
        for (k, v) in values.iter().enumerate() {
            expected[2 + 4 * k..6 + 4 * k].copy_from_slice(v);
        }
        expected[30] = 4;
        assert_eq!(bytes, expected);
        let reply = Reply::parse(&Message::new_checked(&bytes[..]).unwrap()).unwrap();
        assert_eq!(SigningReport::from_reply(&reply), Ok(report));
        assert_eq!(report.dropped(), 15);
        let mut bad = reply;
        bad.values[0] = 4.0;
        assert_eq!(SigningReport::from_reply(&bad), Err(DecodeError::BadField));
        bad = reply;
        bad.index = 0;
        assert_eq!(
            SigningReport::from_reply(&bad),
            Err(DecodeError::WrongCommand)
        );
    }
}
