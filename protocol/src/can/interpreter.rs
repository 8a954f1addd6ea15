//! The Elmo SimplIQ binary interpreter over CAN (spec §6.3).
//!
//! Commands go to a drive in RPDO2 ([`Request`]), answers come back in TPDO2 ([`Reply`]):
//!
//! | Byte | Set, integer (DLC 8) | Set, float (DLC 8) | Query / execute (DLC 4) |
//! |------|----------------------|--------------------|-------------------------|
//! | 0–1  | two upper-case command letters | same | same |
//! | 2    | array index, bits 0–7 | same | same |
//! | 3    | index bits 8–13 in bits 0–5 | same, plus bit 7 (float) | same |
//! | 4–7  | `i32`, little-endian | `f32`, little-endian | absent |
//!
//! A reply has the same layout and always carries a value; bit 6 of byte 3 marks an error, and
//! byte 4 then holds the Elmo error code (see `EC` in the SimplIQ command reference).

use super::{CanFrame, Error, Function, NodeMessage};

/// Byte 3, bit 7: the value is a float.
const FLOAT: u8 = 0x80;
/// Byte 3, bit 6: the reply reports an error.
const ERROR: u8 = 0x40;
/// Byte 3, bits 0–5: index bits 8–13.
const INDEX_HIGH: u8 = 0x3F;

/// A two-letter interpreter command, both letters `A`..=`Z`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Mnemonic([u8; 2]);

impl Mnemonic {
    /// Begin motion.
    pub const BG: Self = Self(*b"BG");
    /// Active (quadrature) current, float.
    pub const IQ: Self = Self(*b"IQ");
    /// Jog velocity, counts/s.
    pub const JV: Self = Self(*b"JV");
    /// Motor on (1) or off (0).
    pub const MO: Self = Self(*b"MO");
    /// PT/PVT motion parameters, indices 1..=6.
    pub const MP: Self = Self(*b"MP");
    /// Absolute position target.
    pub const PA: Self = Self(*b"PA");
    /// PT motion: start index when set, read index when queried.
    pub const PT: Self = Self(*b"PT");
    /// Main position, counts.
    pub const PX: Self = Self(*b"PX");
    /// PT/PVT position table.
    pub const QP: Self = Self(*b"QP");
    /// PVT time table.
    pub const QT: Self = Self(*b"QT");
    /// Stop motion.
    pub const ST: Self = Self(*b"ST");
    /// Torque (current) command, float.
    pub const TC: Self = Self(*b"TC");
    /// Temperature, index 1: drive temperature in °C.
    pub const TI: Self = Self(*b"TI");
    /// Unit mode: 1 torque, 2 speed, 5 position.
    pub const UM: Self = Self(*b"UM");
    /// Main feedback velocity, counts/s.
    pub const VX: Self = Self(*b"VX");

    /// The mnemonic, if both characters are upper-case ASCII letters.
    pub const fn new(chars: [u8; 2]) -> Option<Self> {
        match chars {
            [b'A'..=b'Z', b'A'..=b'Z'] => Some(Self(chars)),
            _ => None,
        }
    }

    /// The two characters.
    pub const fn chars(self) -> [u8; 2] {
        self.0
    }
}

/// An array index, 0..=[`Index::MAX`] (0 for scalar commands).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Index(u16);

impl Index {
    /// The largest index the frame can carry (14 bits).
    pub const MAX: u16 = 0x3FFF;
    /// Index 0, for scalar commands.
    pub const ZERO: Self = Self(0);

    /// The index `i`, if it is at most [`Index::MAX`].
    pub const fn new(i: u16) -> Option<Self> {
        if i <= Self::MAX { Some(Self(i)) } else { None }
    }

    /// The index as a number.
    pub const fn get(self) -> u16 {
        self.0
    }
}

impl From<u8> for Index {
    fn from(i: u8) -> Self {
        Self(u16::from(i))
    }
}

/// A 32-bit value, typed by bit 7 of byte 3.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Value {
    /// A two's-complement integer.
    Int(i32),
    /// An IEEE-754 binary32 float.
    Float(f32),
}

impl Value {
    /// The raw 32-bit word, for a caller that knows a reply's type better than its flag (the
    /// seed read `TC` and `IQ` replies as floats whatever the flag): `f32::from_bits(v.bits())`.
    pub const fn bits(self) -> u32 {
        match self {
            Self::Int(i) => i as u32,
            Self::Float(f) => f.to_bits(),
        }
    }

    /// The type flag of byte 3.
    const fn flag(self) -> u8 {
        match self {
            Self::Int(_) => 0,
            Self::Float(_) => FLOAT,
        }
    }

    /// The value in `bytes`, typed by `flags`.
    fn decode(flags: u8, bytes: [u8; 4]) -> Self {
        let bits = u32::from_le_bytes(bytes);
        if flags & FLOAT == 0 {
            Self::Int(bits as i32)
        } else {
            Self::Float(f32::from_bits(bits))
        }
    }
}

/// A command to a drive (RPDO2).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Request {
    /// Read a variable (`PX`), or run a command without a value (`BG`, `ST`): DLC 4.
    Query {
        /// The command.
        command: Mnemonic,
        /// The array index.
        index: Index,
    },
    /// Assign a variable (`QP[3] = -12345`, `TC = 1.5`): DLC 8.
    Set {
        /// The command.
        command: Mnemonic,
        /// The array index.
        index: Index,
        /// The value, integer or float.
        value: Value,
    },
}

impl NodeMessage for Request {
    const FUNCTION: Function = Function::Rpdo2;

    fn decode(frame: &CanFrame) -> Result<Self, Error> {
        let (command, index, flags, value) = split(frame)?;
        match (frame.dlc(), flags) {
            (4, 0) => Ok(Self::Query { command, index }),
            (8, 0 | FLOAT) => Ok(Self::Set {
                command,
                index,
                value: Value::decode(flags, value),
            }),
            (4 | 8, _) => Err(Error::Malformed),
            _ => Err(Error::WrongLength),
        }
    }

    fn encode(&self) -> (u8, [u8; 8]) {
        match *self {
            Self::Query { command, index } => join(command, index, 0, [0; 4], 4),
            Self::Set {
                command,
                index,
                value,
            } => join_value(command, index, value),
        }
    }
}

/// A drive's answer (TPDO2).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Reply {
    /// The command's value: the variable read, or the echo of a set or execute.
    Value {
        /// The command answered.
        command: Mnemonic,
        /// The array index.
        index: Index,
        /// The value.
        value: Value,
    },
    /// The drive refused the command.
    Error {
        /// The command refused.
        command: Mnemonic,
        /// The array index.
        index: Index,
        /// The Elmo error code (byte 4).
        code: u8,
    },
}

impl NodeMessage for Reply {
    const FUNCTION: Function = Function::Tpdo2;

    /// Needs at least the 4 header bytes; missing value bytes read as zero.
    fn decode(frame: &CanFrame) -> Result<Self, Error> {
        let (command, index, flags, value) = split(frame)?;
        let [code, ..] = value;
        Ok(if flags & ERROR == 0 {
            Self::Value {
                command,
                index,
                value: Value::decode(flags, value),
            }
        } else {
            Self::Error {
                command,
                index,
                code,
            }
        })
    }

    fn encode(&self) -> (u8, [u8; 8]) {
        match *self {
            Self::Value {
                command,
                index,
                value,
            } => join_value(command, index, value),
            Self::Error {
                command,
                index,
                code,
            } => join(command, index, ERROR, [code, 0, 0, 0], 8),
        }
    }
}

/// Command, index, the flag bits of byte 3, and the value bytes, of a frame of at least 4 bytes.
fn split(frame: &CanFrame) -> Result<(Mnemonic, Index, u8, [u8; 4]), Error> {
    let [c0, c1, low, high, value @ ..] = *frame.raw_data();
    if frame.dlc() < 4 {
        return Err(Error::WrongLength);
    }
    let command = Mnemonic::new([c0, c1]).ok_or(Error::Malformed)?;
    let index = Index(u16::from_le_bytes([low, high & INDEX_HIGH]));
    Ok((command, index, high & !INDEX_HIGH, value))
}

/// The frame data for `split`'s parts.
fn join(command: Mnemonic, index: Index, flags: u8, value: [u8; 4], len: u8) -> (u8, [u8; 8]) {
    let [c0, c1] = command.0;
    let [low, high] = index.0.to_le_bytes();
    let [v0, v1, v2, v3] = value;
    (len, [c0, c1, low, high | flags, v0, v1, v2, v3])
}

/// The 8-byte frame data carrying `value`.
fn join_value(command: Mnemonic, index: Index, value: Value) -> (u8, [u8; 8]) {
    join(command, index, value.flag(), value.bits().to_le_bytes(), 8)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::can::NodeId;

    fn frame(id: u16, data: &[u8]) -> CanFrame {
        CanFrame::new(id, data).unwrap()
    }

    #[test]
    fn mnemonics_are_two_capitals() {
        assert_eq!(Mnemonic::new(*b"PX"), Some(Mnemonic::PX));
        assert_eq!(Mnemonic::new(*b"px"), None);
        assert_eq!(Mnemonic::new(*b"P1"), None);
    }

    #[test]
    fn indices_use_fourteen_bits() {
        let node = NodeId::new(1).unwrap();
        let index = Index::new(Index::MAX).unwrap();
        let request = Request::Set {
            command: Mnemonic::QP,
            index,
            value: Value::Float(-0.0),
        };
        let sent = request.to_frame(node);
        assert_eq!(sent.data(), &[b'Q', b'P', 0xFF, 0xBF, 0, 0, 0, 0x80]);
        assert_eq!(Request::parse(&sent), Ok((node, request)));
        assert_eq!(Index::new(Index::MAX + 1), None);
    }

    #[test]
    fn request_lengths_and_flags() {
        let wrong = |data: &[u8]| Request::decode(&frame(0x365, data));
        assert_eq!(wrong(b"PX\0"), Err(Error::WrongLength));
        assert_eq!(wrong(b"PX\0\0\0"), Err(Error::WrongLength));
        assert_eq!(wrong(b"PX\0\x80"), Err(Error::Malformed)); // float flag on a query
        assert_eq!(wrong(b"PX\0\x40\0\0\0\0"), Err(Error::Malformed)); // error flag on a request
        assert_eq!(wrong(b"p!\0\0"), Err(Error::Malformed));
    }

    #[test]
    fn replies_need_the_header_only() {
        let reply = |data: &[u8]| Reply::decode(&frame(0x2E5, data));
        assert_eq!(reply(b"BG\0"), Err(Error::WrongLength));
        let value = Reply::Value {
            command: Mnemonic::BG,
            index: Index::ZERO,
            value: Value::Int(0),
        };
        assert_eq!(reply(b"BG\0\0"), Ok(value));
        let error = Reply::Error {
            command: Mnemonic::BG,
            index: Index::ZERO,
            code: 0,
        };
        assert_eq!(reply(b"BG\0\x40"), Ok(error));
    }

    #[test]
    fn value_bits() {
        assert_eq!(Value::Int(-1).bits(), 0xFFFF_FFFF);
        assert_eq!(Value::Float(1.5).bits(), 0x3FC0_0000);
    }
}
