//! The SDO writes that configure the PDO streaming schedule on a drive (CiA 301 §7.5.2.35–38),
//! as data: the drive manager sends one [`MappingStep`] per cycle, checks its answer, reads
//! the object back and checks the value.
//!
//! For each PDO, in order: disable it (COB-ID bit 31), set its transmission type, clear its
//! mapping (sub 0 = 0: the entries are only writable then), write the entries
//! (`index << 16 | sub << 8 | bits`), set the number of entries, enable it. RPDO3 carries
//! [`PT_POINT`] asynchronously (type 255: acted on at once); TPDO3 carries [`POSITION`],
//! [`HEAD_POINTER`] and [`TAIL_POINTER`] synchronously (type 1: after every SYNC).

use super::pdo::{GROUP_ID, HEAD_POINTER, POSITION, PT_POINT, TAIL_POINTER};
use super::{Function, NodeId, Object, SdoRequest, SdoResponse, SdoValue};

/// COB-ID bit 31: the PDO does not exist (disabled).
pub const PDO_DISABLED: u32 = 0x8000_0000;
/// COB-ID bit 30: no remote transmission request (RTR) for this PDO. Elmo sets it in its
/// default PDO COB-IDs (e.g. RPDO2 0x4000037F).
pub const PDO_NO_RTR: u32 = 0x4000_0000;
/// Transmission type 1: a TPDO sent after every SYNC.
pub const SYNCHRONOUS: u8 = 1;
/// Transmission type 255: an event-driven PDO, acted on (RPDO) as soon as it arrives.
pub const ASYNCHRONOUS: u8 = 255;

/// RPDO3's communication parameters (sub 1 COB-ID, sub 2 transmission type).
pub const RPDO3_COMMUNICATION: u16 = 0x1402;
/// RPDO3's mapping (sub 0 number of entries, subs 1..=8 entries).
pub const RPDO3_MAPPING: u16 = 0x1602;
/// TPDO3's communication parameters.
pub const TPDO3_COMMUNICATION: u16 = 0x1802;
/// TPDO3's mapping.
pub const TPDO3_MAPPING: u16 = 0x1A02;

/// Steps in [`streaming_mapping`].
pub const MAPPING_STEPS: usize = 14;

/// A mapping entry's value: the object and its length in bits.
pub const fn mapping_entry(object: Object, bits: u8) -> u32 {
    (object.index as u32) << 16 | (object.subindex as u32) << 8 | bits as u32
}

/// One SDO write of the mapping and how to check it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MappingStep {
    /// The object written.
    pub object: Object,
    /// The value written; reading the object back gives it again.
    pub value: SdoValue,
}

/// Why a drive did not take a mapping step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MappingRefusal {
    /// The drive aborted the write or the read-back with this CiA 301 abort code.
    Abort(u32),
    /// The value read back is not the one written.
    Mismatch {
        /// What the drive reported.
        read: u32,
    },
    /// The answer is of the wrong kind (an upload answering a write, or the reverse).
    Unexpected,
}

impl MappingStep {
    const fn new(index: u16, subindex: u8, value: SdoValue) -> Self {
        Self {
            object: Object { index, subindex },
            value,
        }
    }

    /// The write.
    pub const fn write(&self) -> SdoRequest {
        SdoRequest::Download {
            object: self.object,
            value: self.value,
        }
    }

    /// The read-back.
    pub const fn read_back(&self) -> SdoRequest {
        SdoRequest::Upload {
            object: self.object,
        }
    }

    /// Checks the answer to [`write`](Self::write). `response` must be about
    /// [`object`](Self::object) (see [`SdoResponse::object`]); answers about other objects
    /// are not this step's.
    pub fn check_write(&self, response: &SdoResponse) -> Result<(), MappingRefusal> {
        match *response {
            SdoResponse::Downloaded { .. } => Ok(()),
            SdoResponse::Abort { code, .. } => Err(MappingRefusal::Abort(code)),
            SdoResponse::Uploaded { .. } => Err(MappingRefusal::Unexpected),
        }
    }

    /// Checks the answer to [`read_back`](Self::read_back): the value written, whatever size
    /// the drive answers with. A COB-ID is compared on bit 31 and the 11-bit identifier only
    /// (bit 30 is the drive's to choose for an RPDO).
    pub fn check_read_back(&self, response: &SdoResponse) -> Result<(), MappingRefusal> {
        let read = match *response {
            SdoResponse::Uploaded { value, .. } => value.get(),
            SdoResponse::Abort { code, .. } => return Err(MappingRefusal::Abort(code)),
            SdoResponse::Downloaded { .. } => return Err(MappingRefusal::Unexpected),
        };
        let mask = match self.object.subindex {
            1 if is_communication(self.object.index) => PDO_DISABLED | 0x7FF,
            _ => u32::MAX,
        };
        if (read ^ self.value.get()) & mask == 0 {
            Ok(())
        } else {
            Err(MappingRefusal::Mismatch { read })
        }
    }
}

/// True for a PDO communication parameter object (0x1400..=0x15FF, 0x1800..=0x19FF).
const fn is_communication(index: u16) -> bool {
    matches!(index, 0x1400..=0x15FF | 0x1800..=0x19FF)
}

/// The write of the group id `group` (Elmo 0x2040), checked like a mapping step. It takes
/// effect at the next NMT reset communication, which also returns the PDOs to their
/// power-on configuration: write it, reset, start, then map.
pub const fn group_id_step(group: NodeId) -> MappingStep {
    MappingStep {
        object: GROUP_ID,
        value: SdoValue::U8(group.get()),
    }
}

/// The ordered steps that map RPDO3 and TPDO3 of `node` for PDO streaming.
pub const fn streaming_mapping(node: NodeId) -> [MappingStep; MAPPING_STEPS] {
    let rpdo = Function::Rpdo3.cob_id(node) as u32 | PDO_NO_RTR;
    let tpdo = Function::Tpdo3.cob_id(node) as u32 | PDO_NO_RTR;
    let u8 = SdoValue::U8;
    let u32 = SdoValue::U32;
    [
        MappingStep::new(RPDO3_COMMUNICATION, 1, u32(rpdo | PDO_DISABLED)),
        MappingStep::new(RPDO3_COMMUNICATION, 2, u8(ASYNCHRONOUS)),
        MappingStep::new(RPDO3_MAPPING, 0, u8(0)),
        MappingStep::new(RPDO3_MAPPING, 1, u32(mapping_entry(PT_POINT, 32))),
        MappingStep::new(RPDO3_MAPPING, 0, u8(1)),
        MappingStep::new(RPDO3_COMMUNICATION, 1, u32(rpdo)),
        MappingStep::new(TPDO3_COMMUNICATION, 1, u32(tpdo | PDO_DISABLED)),
        MappingStep::new(TPDO3_COMMUNICATION, 2, u8(SYNCHRONOUS)),
        MappingStep::new(TPDO3_MAPPING, 0, u8(0)),
        MappingStep::new(TPDO3_MAPPING, 1, u32(mapping_entry(POSITION, 32))),
        MappingStep::new(TPDO3_MAPPING, 2, u32(mapping_entry(HEAD_POINTER, 16))),
        MappingStep::new(TPDO3_MAPPING, 3, u32(mapping_entry(TAIL_POINTER, 16))),
        MappingStep::new(TPDO3_MAPPING, 0, u8(3)),
        MappingStep::new(TPDO3_COMMUNICATION, 1, u32(tpdo)),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::can::NodeMessage;

    #[test]
    fn the_mapping_of_node_101_on_the_wire() {
        let node = NodeId::new(101).unwrap();
        let frames: Vec<[u8; 8]> = streaming_mapping(node)
            .iter()
            .map(|step| {
                let frame = step.write().to_frame(node);
                assert_eq!(frame.id(), 0x665);
                *frame.raw_data()
            })
            .collect();
        let expected: [[u8; 8]; MAPPING_STEPS] = [
            [0x23, 0x02, 0x14, 1, 0x65, 0x04, 0x00, 0xC0], // RPDO3 off
            [0x2F, 0x02, 0x14, 2, 0xFF, 0, 0, 0],          // asynchronous
            [0x2F, 0x02, 0x16, 0, 0, 0, 0, 0],             // no entries
            [0x23, 0x02, 0x16, 1, 0x20, 0x00, 0x02, 0x20], // 0x2002:0, 32 bits
            [0x2F, 0x02, 0x16, 0, 1, 0, 0, 0],             // one entry
            [0x23, 0x02, 0x14, 1, 0x65, 0x04, 0x00, 0x40], // RPDO3 on
            [0x23, 0x02, 0x18, 1, 0xE5, 0x03, 0x00, 0xC0], // TPDO3 off
            [0x2F, 0x02, 0x18, 2, 1, 0, 0, 0],             // synchronous
            [0x2F, 0x02, 0x1A, 0, 0, 0, 0, 0],
            [0x23, 0x02, 0x1A, 1, 0x20, 0x00, 0x64, 0x60], // 0x6064:0, 32 bits
            [0x23, 0x02, 0x1A, 2, 0x10, 0x00, 0x11, 0x2F], // 0x2F11:0, 16 bits
            [0x23, 0x02, 0x1A, 3, 0x10, 0x00, 0x12, 0x2F], // 0x2F12:0, 16 bits
            [0x2F, 0x02, 0x1A, 0, 3, 0, 0, 0],
            [0x23, 0x02, 0x18, 1, 0xE5, 0x03, 0x00, 0x40], // TPDO3 on
        ];
        assert_eq!(frames, expected);
    }

    #[test]
    fn checks_of_the_answers() {
        let node = NodeId::new(5).unwrap();
        let [enable_rpdo, ..] = streaming_mapping(node);
        let object = enable_rpdo.object;
        let done = SdoResponse::Downloaded { object };
        assert_eq!(enable_rpdo.check_write(&done), Ok(()));
        let abort = SdoResponse::Abort {
            object,
            code: abort_code(),
        };
        assert_eq!(
            enable_rpdo.check_write(&abort),
            Err(MappingRefusal::Abort(abort_code()))
        );
        assert_eq!(
            enable_rpdo.check_read_back(&done),
            Err(MappingRefusal::Unexpected)
        );
        // The COB-ID reads back with or without the RTR bit; the identifier and bit 31 count.
        let read = |value| SdoResponse::Uploaded {
            object,
            value: SdoValue::U32(value),
        };
        assert_eq!(enable_rpdo.check_read_back(&read(0xC000_0405)), Ok(()));
        assert_eq!(enable_rpdo.check_read_back(&read(0x8000_0405)), Ok(()));
        assert_eq!(
            enable_rpdo.check_read_back(&read(0x4000_0405)),
            Err(MappingRefusal::Mismatch { read: 0x4000_0405 })
        );
        // Other entries compare whole, whatever size the drive answers with.
        let entries = streaming_mapping(node)[4];
        let entries_read = |value| SdoResponse::Uploaded {
            object: entries.object,
            value,
        };
        assert_eq!(
            entries.check_read_back(&entries_read(SdoValue::U32(1))),
            Ok(())
        );
        assert_eq!(
            entries.check_read_back(&entries_read(SdoValue::U8(0))),
            Err(MappingRefusal::Mismatch { read: 0 })
        );
    }

    #[test]
    fn the_group_id_write() {
        let step = group_id_step(NodeId::new(120).unwrap());
        let frame = step.write().to_frame(NodeId::new(101).unwrap());
        assert_eq!(frame.data(), &[0x2F, 0x40, 0x20, 0, 120, 0, 0, 0]);
        let read = SdoResponse::Uploaded {
            object: GROUP_ID,
            value: SdoValue::U8(120),
        };
        assert_eq!(step.check_read_back(&read), Ok(()));
    }

    fn abort_code() -> u32 {
        crate::can::sdo_abort::NOT_MAPPABLE
    }
}
