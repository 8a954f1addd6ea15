//! The status request `SQ` and its replies `QS` (docs/protocol.md).
//!
//! Index 0 asks for the state ([`StatusReport`]: seven numbers), index 1 for the robot's name
//! ([`RobotName`]: 28 ASCII bytes where the floats would be). Any other index is refused with
//! `ER24 Cmd SQ bad index`.

use super::message::datagram;
use super::{Command, DecodeError, DriveStatus, MESSAGE_LEN, Message, Mode, Reply, VALUES};

/// `SQ` index of the state report.
pub const STATUS_INDEX: u8 = 0;
/// `SQ` index of the robot name.
pub const NAME_INDEX: u8 = 1;
/// Bytes of the robot name in a `QS` reply (bytes 2..30).
pub const NAME_LEN: usize = 28;

/// What the arm is doing (`QS` f4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Motion {
    /// Holding still (or mode off).
    Holding = 0,
    /// A joint move (`jB`).
    JointMove = 1,
    /// A Cartesian move or shape (`BG`).
    CartesianMove = 2,
    /// A joint via-point sequence (`jE`).
    JointSequence = 3,
    /// A Cartesian via-point sequence (`VE`).
    CartesianSequence = 4,
    /// A twist or joint-rate stream (`TW`, `jW`), until it has ramped to rest.
    Streaming = 5,
    /// Coming to rest after a stop (`ST`, `CM` or `OF` while moving, a workspace limit, IK
    /// divergence); `SQ` index 2 says why.
    Stopping = 6,
}

impl Motion {
    /// Every motion, by code.
    pub const ALL: [Self; 7] = [
        Self::Holding,
        Self::JointMove,
        Self::CartesianMove,
        Self::JointSequence,
        Self::CartesianSequence,
        Self::Streaming,
        Self::Stopping,
    ];

    /// The motion with this code.
    pub fn from_code(code: u8) -> Option<Self> {
        Self::ALL.into_iter().find(|m| *m as u8 == code)
    }
}

/// The `QS` reply to `SQ` index 0.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StatusReport {
    /// f0: control mode, as `CM` takes it (0 off, 1 joint, 2 Cartesian).
    pub mode: Mode,
    /// f1: the drives' state.
    pub drives: DriveStatus,
    /// f2: the current drive fault's code (30..=39, the `NN` of its `ERNN` text); 0 for none.
    pub fault: u8,
    /// f3: the number of joints.
    pub joints: u8,
    /// f4: what the arm is doing.
    pub motion: Motion,
    /// f5: requests refused (answered with an `ER` text) since the controller started.
    pub refused: u32,
    /// f6: seconds since the controller started.
    pub uptime: f32,
}

impl StatusReport {
    /// The reply, index 0.
    pub fn to_reply(&self) -> Reply {
        // u32 → f32 rounds above 2²⁴ refusals; the count is for people, not for arithmetic.
        let values = [
            f32::from(self.mode.value()),
            f32::from(self.drives as u8),
            f32::from(self.fault),
            f32::from(self.joints),
            f32::from(self.motion as u8),
            self.refused as f32,
            self.uptime,
        ];
        Reply {
            command: Command::Status,
            values,
            index: STATUS_INDEX,
        }
    }

    /// Decodes a `QS` index-0 reply (on the client side).
    pub fn from_reply(reply: &Reply) -> Result<Self, DecodeError> {
        if reply.command != Command::Status || reply.index != STATUS_INDEX {
            return Err(DecodeError::WrongCommand);
        }
        let [mode, drives, fault, joints, motion, refused, uptime] = reply.values;
        let report = || -> Option<Self> {
            Some(Self {
                mode: Mode::ALL
                    .into_iter()
                    .find(|m| Some(m.value()) == small(mode))?,
                drives: DriveStatus::from_code(small(drives)?)?,
                fault: small(fault)?,
                joints: small(joints)?,
                motion: Motion::from_code(small(motion)?)?,
                refused: whole(refused)?,
                uptime: Some(uptime).filter(|t| t.is_finite())?,
            })
        };
        report().ok_or(DecodeError::BadField)
    }
}

/// A float that holds a whole number 0..=255.
fn small(v: f32) -> Option<u8> {
    whole(v).and_then(|n| u8::try_from(n).ok())
}

/// A float that holds a whole non-negative number.
pub(super) fn whole(v: f32) -> Option<u32> {
    // The cast saturates; the comparison rejects fractions, NaN and out-of-range values.
    let n = v as u32;
    (v >= 0.0 && n as f32 == v).then_some(n)
}

/// The `QS` reply to `SQ` index 1: the robot's name, ASCII, NUL-padded (bytes 2..30), index 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct RobotName {
    bytes: [u8; NAME_LEN],
    len: u8,
}

impl RobotName {
    /// The first [`NAME_LEN`] bytes of `name`; anything but printable ASCII becomes `?`.
    pub fn new(name: &str) -> Self {
        let mut out = Self {
            bytes: [0; NAME_LEN],
            len: 0,
        };
        for (slot, b) in out.bytes.iter_mut().zip(name.bytes()) {
            *slot = if b == b' ' || b.is_ascii_graphic() {
                b
            } else {
                b'?'
            };
            out.len += 1;
        }
        out
    }

    /// The name's bytes in a received `QS` index-1 reply (up to the first NUL).
    pub fn parse<T: AsRef<[u8]>>(message: &Message<T>) -> Result<Self, DecodeError> {
        if message.command() != Command::Status.reply_chars() || message.index() != NAME_INDEX {
            return Err(DecodeError::WrongCommand);
        }
        let bytes = message.bytes();
        let name = bytes.get(2..2 + NAME_LEN).unwrap_or_default();
        let end = name.iter().position(|&b| b == 0).unwrap_or(name.len());
        let name = name.get(..end).unwrap_or_default();
        Ok(Self::new(core::str::from_utf8(name).unwrap_or("?")))
    }

    /// The name.
    pub fn as_str(&self) -> &str {
        let bytes = self.bytes.get(..usize::from(self.len)).unwrap_or_default();
        core::str::from_utf8(bytes).unwrap_or_default()
    }

    /// Writes the reply into `message`.
    pub fn emit<T: AsRef<[u8]> + AsMut<[u8]>>(&self, message: &mut Message<T>) {
        message.encode(Command::Status.reply_chars(), &[0.0; VALUES], NAME_INDEX);
        let mut bytes = message.bytes();
        for (slot, b) in bytes.iter_mut().skip(2).zip(self.bytes) {
            *slot = b;
        }
        message.set_bytes(&bytes);
    }

    /// The reply as a datagram.
    pub fn to_bytes(&self) -> [u8; MESSAGE_LEN] {
        datagram(|message| self.emit(message))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report() -> StatusReport {
        StatusReport {
            mode: Mode::Cartesian,
            drives: DriveStatus::Faulted,
            fault: 33,
            joints: 6,
            motion: Motion::CartesianSequence,
            refused: 7,
            uptime: 12.5,
        }
    }

    #[test]
    fn the_report_is_seven_floats_at_index_0() {
        let bytes = report().to_reply().to_bytes();
        let mut expected = [0u8; MESSAGE_LEN];
        expected[..2].copy_from_slice(b"QS");
        for (k, v) in [2.0f32, 4.0, 33.0, 6.0, 4.0, 7.0, 12.5].iter().enumerate() {
            expected[2 + 4 * k..6 + 4 * k].copy_from_slice(&v.to_le_bytes());
        }
        assert_eq!(bytes, expected);
        // f1 = 4.0 is 00 00 80 40, little-endian.
        assert_eq!(bytes[6..10], [0x00, 0x00, 0x80, 0x40]);
        let reply = Reply::parse(&Message::new_checked(&bytes[..]).unwrap()).unwrap();
        assert_eq!(StatusReport::from_reply(&reply), Ok(report()));
    }

    #[test]
    fn a_report_with_invalid_codes_does_not_decode() {
        for (field, bad) in [
            (0, 3.0),
            (1, 5.0),
            (2, 0.5),
            (4, 9.0),
            (5, -1.0),
            (6, f32::NAN),
        ] {
            let mut reply = report().to_reply();
            reply.values[field] = bad;
            assert_eq!(
                StatusReport::from_reply(&reply),
                Err(DecodeError::BadField),
                "f{field} = {bad}"
            );
        }
        let mut reply = report().to_reply();
        reply.index = NAME_INDEX;
        assert_eq!(
            StatusReport::from_reply(&reply),
            Err(DecodeError::WrongCommand)
        );
    }

    #[test]
    fn the_name_fills_bytes_2_to_30() {
        let bytes = RobotName::new("ranger-mk1").to_bytes();
        let mut expected = [0u8; MESSAGE_LEN];
        expected[..12].copy_from_slice(b"QSranger-mk1");
        expected[30] = 1;
        assert_eq!(bytes, expected);
        let parsed = RobotName::parse(&Message::new_checked(&bytes[..]).unwrap()).unwrap();
        assert_eq!(parsed.as_str(), "ranger-mk1");
    }

    #[test]
    fn a_long_name_is_truncated_to_28_bytes() {
        let name = RobotName::new("an-arm-with-a-very-long-name-indeed\u{e9}");
        assert_eq!(name.as_str(), "an-arm-with-a-very-long-name");
        let bytes = name.to_bytes();
        assert_eq!(&bytes[2..30], b"an-arm-with-a-very-long-name");
        assert_eq!(bytes[30], NAME_INDEX);
        assert_eq!(RobotName::new("tab\there").as_str(), "tab?here");
    }
}
