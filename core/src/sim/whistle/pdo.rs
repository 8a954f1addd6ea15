//! The simulated drive's PDO configuration: RPDO3 and TPDO3 in its object dictionary (0x1402,
//! 0x1602, 0x1802, 0x1A02) and the group id (0x2040), written and read by SDO with CiA 301's
//! rules, and the PDOs' payloads.
//!
//! Rules (CiA 301 §7.5.2.35–38; MAN-CAN301IG §5 for Elmo's transmission types):
//!
//! * A PDO is valid while bit 31 of its COB-ID is clear. Its identifier can only change while
//!   it is not (else abort 0x0609_0030); bit 29 (extended frame) is refused the same way.
//! * Transmission types 1 (synchronous), 254 and 255 (event-driven) are taken, others refused
//!   with 0x0609_0030 (the Elmo manual's list).
//! * The mapping (sub 0 and the entries) can only be written while the PDO is not valid (else
//!   0x0800_0022), and an entry only while sub 0 is 0 (else 0x0800_0022). An entry must name
//!   an object this PDO can carry with its length (unknown object 0x0602_0000, wrong direction
//!   or length 0x0604_0041). Sub 0 counts the entries and must not exceed 64 bits
//!   (0x0604_0042).
//! * Sub 0 of a communication object is read-only (0x0601_0002); other sub-indices do not
//!   exist (0x0609_0011).
//!
//! The objects a PDO can carry are the PDO streaming schedule's: RPDO3 the PT point
//! ([`pdo::PT_POINT`], 32 bits), TPDO3 the position and the PT head and tail pointers.

use armgate_protocol::can::pdo::{self, HEAD_POINTER, POSITION, PT_POINT, TAIL_POINTER};
use armgate_protocol::can::{
    ASYNCHRONOUS, Function, NodeId, Object, PDO_DISABLED, PDO_NO_RTR, RPDO3_COMMUNICATION,
    RPDO3_MAPPING, SYNCHRONOUS, SdoValue, TPDO3_COMMUNICATION, TPDO3_MAPPING, sdo_abort,
};

/// Entries a mapping holds.
const MAX_ENTRIES: usize = 8;
/// Transmission type 254: event-driven, manufacturer-specific.
const EVENT_DRIVEN: u8 = 254;
/// COB-ID bit 29: a 29-bit identifier.
const EXTENDED_FRAME: u32 = 0x2000_0000;

/// One PDO's communication and mapping parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PdoParameters {
    /// Sub 1 of the communication object.
    pub cob_id: u32,
    /// Sub 2 of the communication object.
    pub transmission: u8,
    /// Sub 0 of the mapping object: entries in use.
    pub count: u8,
    /// Subs 1..=8 of the mapping object.
    pub entries: [u32; MAX_ENTRIES],
}

impl PdoParameters {
    /// A PDO that does not exist (bit 31 set), with nothing mapped.
    const fn disabled(cob_id: u16, transmission: u8) -> Self {
        Self {
            cob_id: PDO_DISABLED | PDO_NO_RTR | cob_id as u32,
            transmission,
            count: 0,
            entries: [0; MAX_ENTRIES],
        }
    }

    /// True if the PDO exists (bit 31 clear).
    pub const fn valid(&self) -> bool {
        self.cob_id & PDO_DISABLED == 0
    }

    /// The 11-bit identifier.
    pub const fn id(&self) -> u16 {
        (self.cob_id & 0x7FF) as u16
    }

    /// The mapped entries, in order.
    pub fn mapped(&self) -> impl Iterator<Item = u32> + '_ {
        self.entries.iter().copied().take(usize::from(self.count))
    }
}

/// Which PDO.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Which {
    Rpdo3,
    Tpdo3,
}

/// The PDO objects of a simulated drive's object dictionary.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PdoObjects {
    /// RPDO3: PT points in.
    pub rpdo3: PdoParameters,
    /// TPDO3: feedback out.
    pub tpdo3: PdoParameters,
    /// 0x2040 as written; it takes effect at the next reset communication.
    pub group_written: u8,
}

impl PdoObjects {
    /// The power-on values for `node`: both PDOs at their default identifiers, not valid,
    /// nothing mapped (ASSUMED: a Whistle's defaults for PDO3 are not in the manual), and no
    /// group id.
    pub const fn new(node: NodeId) -> Self {
        Self {
            rpdo3: PdoParameters::disabled(Function::Rpdo3.cob_id(node), ASYNCHRONOUS),
            tpdo3: PdoParameters::disabled(Function::Tpdo3.cob_id(node), EVENT_DRIVEN),
            group_written: 0,
        }
    }

    /// True if this module holds `object`'s index.
    pub const fn holds(object: Object) -> bool {
        matches!(
            object.index,
            RPDO3_COMMUNICATION | RPDO3_MAPPING | TPDO3_COMMUNICATION | TPDO3_MAPPING
        ) || object.index == pdo::GROUP_ID.index
    }

    fn pdo_mut(&mut self, which: Which) -> &mut PdoParameters {
        match which {
            Which::Rpdo3 => &mut self.rpdo3,
            Which::Tpdo3 => &mut self.tpdo3,
        }
    }

    /// An SDO write; `Err` is the abort code.
    pub fn download(&mut self, object: Object, value: SdoValue) -> Result<(), u32> {
        let v = value.get();
        match (object.index, object.subindex) {
            (RPDO3_COMMUNICATION, sub) => self.write_communication(Which::Rpdo3, sub, v),
            (TPDO3_COMMUNICATION, sub) => self.write_communication(Which::Tpdo3, sub, v),
            (RPDO3_MAPPING, sub) => self.write_mapping(Which::Rpdo3, sub, v),
            (TPDO3_MAPPING, sub) => self.write_mapping(Which::Tpdo3, sub, v),
            (index, 0) if index == pdo::GROUP_ID.index => {
                self.group_written = u8::try_from(v)
                    .ok()
                    .filter(|&id| id <= 127)
                    .ok_or(sdo_abort::INVALID_VALUE)?;
                Ok(())
            }
            (index, _) if index == pdo::GROUP_ID.index => Err(sdo_abort::NO_SUBINDEX),
            _ => Err(sdo_abort::NO_OBJECT),
        }
    }

    /// An SDO read; `Err` is the abort code.
    pub fn upload(&self, object: Object) -> Result<SdoValue, u32> {
        let (pdo, communication) = match object.index {
            RPDO3_COMMUNICATION => (&self.rpdo3, true),
            TPDO3_COMMUNICATION => (&self.tpdo3, true),
            RPDO3_MAPPING => (&self.rpdo3, false),
            TPDO3_MAPPING => (&self.tpdo3, false),
            index if index == pdo::GROUP_ID.index && object.subindex == 0 => {
                return Ok(SdoValue::U8(self.group_written));
            }
            index if index == pdo::GROUP_ID.index => return Err(sdo_abort::NO_SUBINDEX),
            _ => return Err(sdo_abort::NO_OBJECT),
        };
        match (communication, object.subindex) {
            (true, 0) => Ok(SdoValue::U8(2)),
            (true, 1) => Ok(SdoValue::U32(pdo.cob_id)),
            (true, 2) => Ok(SdoValue::U8(pdo.transmission)),
            (false, 0) => Ok(SdoValue::U8(pdo.count)),
            (false, sub) => pdo
                .entries
                .get(usize::from(sub).wrapping_sub(1))
                .map(|&entry| SdoValue::U32(entry))
                .ok_or(sdo_abort::NO_SUBINDEX),
            (true, _) => Err(sdo_abort::NO_SUBINDEX),
        }
    }

    fn write_communication(&mut self, which: Which, sub: u8, value: u32) -> Result<(), u32> {
        let pdo = self.pdo_mut(which);
        match sub {
            0 => Err(sdo_abort::READ_ONLY),
            1 => {
                let changes_id = (value ^ pdo.cob_id) & 0x7FF != 0;
                let stays_valid = pdo.valid() && value & PDO_DISABLED == 0;
                if value & EXTENDED_FRAME != 0 || (stays_valid && changes_id) {
                    return Err(sdo_abort::INVALID_VALUE);
                }
                pdo.cob_id = value;
                Ok(())
            }
            2 => match u8::try_from(value) {
                Ok(t @ (SYNCHRONOUS | EVENT_DRIVEN | ASYNCHRONOUS)) => {
                    pdo.transmission = t;
                    Ok(())
                }
                _ => Err(sdo_abort::INVALID_VALUE),
            },
            _ => Err(sdo_abort::NO_SUBINDEX),
        }
    }

    fn write_mapping(&mut self, which: Which, sub: u8, value: u32) -> Result<(), u32> {
        let pdo = self.pdo_mut(which);
        if pdo.valid() {
            return Err(sdo_abort::DEVICE_STATE);
        }
        if sub == 0 {
            let count = u8::try_from(value)
                .ok()
                .filter(|&n| usize::from(n) <= MAX_ENTRIES)
                .ok_or(sdo_abort::INVALID_VALUE)?;
            let bits: u32 = pdo
                .entries
                .iter()
                .take(usize::from(count))
                .map(|entry| entry & 0xFF)
                .sum();
            if bits > 64 {
                return Err(sdo_abort::PDO_TOO_LONG);
            }
            pdo.count = count;
            return Ok(());
        }
        if pdo.count != 0 {
            return Err(sdo_abort::DEVICE_STATE);
        }
        let slot = pdo
            .entries
            .get_mut(usize::from(sub).wrapping_sub(1))
            .ok_or(sdo_abort::NO_SUBINDEX)?;
        check_entry(which, value)?;
        *slot = value;
        Ok(())
    }
}

/// Whether `entry` (`index << 16 | sub << 8 | bits`) can go into `which`.
fn check_entry(which: Which, entry: u32) -> Result<(), u32> {
    let object = Object {
        index: (entry >> 16) as u16,
        subindex: (entry >> 8) as u8,
    };
    let bits = entry & 0xFF;
    let expected = match object {
        PT_POINT => (Which::Rpdo3, 32),
        POSITION => (Which::Tpdo3, 32),
        HEAD_POINTER | TAIL_POINTER => (Which::Tpdo3, 16),
        _ => return Err(sdo_abort::NO_OBJECT),
    };
    if expected == (which, bits) {
        Ok(())
    } else {
        Err(sdo_abort::NOT_MAPPABLE)
    }
}

/// The values a TPDO can carry, sampled at one instant.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sampled {
    /// `PX` (counts).
    pub position: i32,
    /// The PT write pointer.
    pub head: u16,
    /// The PT read pointer.
    pub tail: u16,
}

/// The data of `pdo` carrying `values`: each mapped object's low bytes, little-endian, in
/// mapping order (at most 8 bytes, which the mapping rules guarantee).
pub fn tpdo_payload(pdo: &PdoParameters, values: Sampled) -> heapless::Vec<u8, 8> {
    let mut data = heapless::Vec::new();
    for entry in pdo.mapped() {
        let object = Object {
            index: (entry >> 16) as u16,
            subindex: (entry >> 8) as u8,
        };
        let value: u32 = match object {
            POSITION => values.position as u32,
            HEAD_POINTER => u32::from(values.head),
            TAIL_POINTER => u32::from(values.tail),
            _ => 0,
        };
        let bytes = usize::try_from((entry & 0xFF) / 8).unwrap_or(0);
        for byte in value.to_le_bytes().into_iter().take(bytes) {
            // The mapping rules keep the total within 8 bytes; a full buffer drops the rest.
            let _ = data.push(byte);
        }
    }
    data
}

/// What an RPDO's data holds, read through its mapping.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RpdoContent {
    /// A PT point (counts).
    Point(i32),
    /// The mapping has no PT point (nothing mapped).
    NotMapped,
    /// The data is shorter than the mapping.
    TooShort,
}

/// The content of an RPDO's `data` as mapped by `pdo`.
pub fn rpdo_content(pdo: &PdoParameters, data: &[u8]) -> RpdoContent {
    let mut offset = 0usize;
    let mut content = RpdoContent::NotMapped;
    let pt_point = armgate_protocol::can::mapping_entry(PT_POINT, 32);
    for entry in pdo.mapped() {
        let bytes = usize::try_from((entry & 0xFF) / 8).unwrap_or(0);
        let Some(field) = data.get(offset..offset + bytes) else {
            return RpdoContent::TooShort;
        };
        if let (true, [a, b, c, d]) = (entry == pt_point, field) {
            content = RpdoContent::Point(i32::from_le_bytes([*a, *b, *c, *d]));
        }
        offset += bytes;
    }
    content
}
