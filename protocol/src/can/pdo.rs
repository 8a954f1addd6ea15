//! The process data objects of the PDO streaming schedule: one PT point per drive and cycle in
//! RPDO3, and the drive's position and PT pointers in a synchronous TPDO3.
//!
//! | PDO | COB-ID | DLC | Bytes | Mapped objects |
//! |---|---|---|---|---|
//! | RPDO3 (controller → drive), asynchronous (type 255) | `0x400 + node` | 4 | `i32` LE | [`PT_POINT`]: the point, written at the drive's PT write pointer |
//! | TPDO3 (drive → controller), synchronous (type 1) | `0x380 + node` | 8 | `i32` LE, `u16` LE, `u16` LE | [`POSITION`], [`HEAD_POINTER`], [`TAIL_POINTER`], sampled at the SYNC |
//!
//! docs/drives.md ("Elmo objects the PDO schedule relies on") says which of these the Elmo
//! manual confirms and which the simulation assumes.

use super::{CanFrame, Error, Function, NodeMessage, Object};

/// The Elmo PT-type motion command object (MAN-CAN301IG §5, "Example of RPDO mapping":
/// `0x2002`): a point written to it goes to the PT table at the write pointer `MP[6]`, which
/// then advances. ASSUMED: mapped with 32 bits, one position per frame; the manual's example
/// maps it with 64 bits (two positions per frame).
pub const PT_POINT: Object = Object {
    index: 0x2002,
    subindex: 0,
};

/// The main position `PX` in counts, INTEGER32. ASSUMED: the CiA 402 "position actual value"
/// object, which SimplIQ firmware serves as `PX`.
pub const POSITION: Object = Object {
    index: 0x6064,
    subindex: 0,
};

/// Elmo 0x2F11 "PVT head pointer", UNSIGNED16: the table index the next point will be written
/// to (the write pointer).
pub const HEAD_POINTER: Object = Object {
    index: 0x2F11,
    subindex: 0,
};

/// Elmo 0x2F12 "PVT tail pointer", UNSIGNED16: the table index the motion reads next (the read
/// pointer). Only available mapped into a synchronous TPDO, never by SDO.
pub const TAIL_POINTER: Object = Object {
    index: 0x2F12,
    subindex: 0,
};

/// Elmo 0x2040 "ID for synchronized commands" (coordinate system group ID), UNSIGNED8
/// (MAN-CAN301IG §13): a drive also takes the frames addressed to this node id, and answers
/// with its own. Written by SDO, it takes effect at the next NMT reset communication (which
/// also resets the PDO configuration, so it goes first). One `BG` in RPDO2 to the group id
/// begins every drive of the group at once.
pub const GROUP_ID: Object = Object {
    index: 0x2040,
    subindex: 0,
};

/// RPDO3: the next PT point for a drive, in encoder counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PtPoint {
    /// The position (counts).
    pub position: i32,
}

impl NodeMessage for PtPoint {
    const FUNCTION: Function = Function::Rpdo3;

    fn decode(frame: &CanFrame) -> Result<Self, Error> {
        let [p0, p1, p2, p3, ..] = *frame.raw_data();
        if frame.dlc() != 4 {
            return Err(Error::WrongLength);
        }
        Ok(Self {
            position: i32::from_le_bytes([p0, p1, p2, p3]),
        })
    }

    fn encode(&self) -> (u8, [u8; 8]) {
        let [p0, p1, p2, p3] = self.position.to_le_bytes();
        (4, [p0, p1, p2, p3, 0, 0, 0, 0])
    }
}

/// TPDO3: what a drive reports after each SYNC, sampled when the SYNC arrived.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PtFeedback {
    /// The main position `PX` (counts).
    pub position: i32,
    /// The PT write pointer (0x2F11): where the next point will be written.
    pub head: u16,
    /// The PT read pointer (0x2F12): the table index the motion reads next.
    pub tail: u16,
}

impl NodeMessage for PtFeedback {
    const FUNCTION: Function = Function::Tpdo3;

    fn decode(frame: &CanFrame) -> Result<Self, Error> {
        let [p0, p1, p2, p3, h0, h1, t0, t1] = *frame.raw_data();
        if frame.dlc() != 8 {
            return Err(Error::WrongLength);
        }
        Ok(Self {
            position: i32::from_le_bytes([p0, p1, p2, p3]),
            head: u16::from_le_bytes([h0, h1]),
            tail: u16::from_le_bytes([t0, t1]),
        })
    }

    fn encode(&self) -> (u8, [u8; 8]) {
        let [p0, p1, p2, p3] = self.position.to_le_bytes();
        let [h0, h1] = self.head.to_le_bytes();
        let [t0, t1] = self.tail.to_le_bytes();
        (8, [p0, p1, p2, p3, h0, h1, t0, t1])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::can::NodeId;

    fn node() -> NodeId {
        NodeId::new(101).unwrap()
    }

    #[test]
    fn pt_point_literal_bytes() {
        let point = PtPoint { position: -12345 };
        let frame = point.to_frame(node());
        assert_eq!(frame.id(), 0x465);
        assert_eq!(frame.data(), &[0xC7, 0xCF, 0xFF, 0xFF]);
        assert_eq!(PtPoint::parse(&frame), Ok((node(), point)));
        let wrong_length = CanFrame::new(0x465, &[0xC7, 0xCF, 0xFF, 0xFF, 0]).unwrap();
        assert_eq!(PtPoint::parse(&wrong_length), Err(Error::WrongLength));
        let rpdo2 = CanFrame::new(0x365, &[0xC7, 0xCF, 0xFF, 0xFF]).unwrap();
        assert_eq!(PtPoint::parse(&rpdo2), Err(Error::WrongId));
    }

    #[test]
    fn feedback_literal_bytes() {
        let bytes = [0x39, 0x30, 0, 0, 0x05, 0x00, 0x02, 0x00];
        let frame = CanFrame::new(0x3E5, &bytes).unwrap();
        let feedback = PtFeedback {
            position: 12345,
            head: 5,
            tail: 2,
        };
        assert_eq!(PtFeedback::parse(&frame), Ok((node(), feedback)));
        assert_eq!(feedback.to_frame(node()), frame);
        let negative = PtFeedback {
            position: -1,
            head: 0x0102,
            tail: 0xFFFF,
        };
        assert_eq!(
            negative.encode(),
            (8, [0xFF, 0xFF, 0xFF, 0xFF, 0x02, 0x01, 0xFF, 0xFF])
        );
        let short = CanFrame::new(0x3E5, &bytes[..6]).unwrap();
        assert_eq!(PtFeedback::parse(&short), Err(Error::WrongLength));
    }
}
