//! Expedited SDO transfers (requests `0x600 + node`, responses `0x580 + node`).
//!
//! Every SDO frame has 8 bytes: the command specifier, the object index (little-endian), the
//! sub-index, and up to 4 data bytes. Only expedited transfers of 1, 2 or 4 bytes are supported:
//! enough to configure heartbeats (objects 0x1016 and 0x1017), map PDOs (see
//! [`streaming_mapping`](super::streaming_mapping)) and read small objects.

use super::{CanFrame, Error, Function, NodeId, NodeMessage};

/// Command specifiers.
mod cs {
    /// Expedited download request; bits 2–3 hold 4 − size.
    pub const DOWNLOAD: u8 = 0x23;
    /// Upload request.
    pub const UPLOAD: u8 = 0x40;
    /// Download acknowledgement.
    pub const DOWNLOADED: u8 = 0x60;
    /// Expedited upload response; bits 2–3 hold 4 − size.
    pub const UPLOADED: u8 = 0x43;
    /// Abort transfer.
    pub const ABORT: u8 = 0x80;
    /// The bits of an expedited specifier that hold 4 − size.
    pub const SIZE: u8 = 0x0C;
}

/// CiA 301 SDO abort codes (the `code` of [`SdoResponse::Abort`]) that the drives and their
/// simulation use.
pub mod abort {
    /// Unsupported access to an object.
    pub const UNSUPPORTED_ACCESS: u32 = 0x0601_0000;
    /// Attempt to read a write-only object.
    pub const WRITE_ONLY: u32 = 0x0601_0001;
    /// Attempt to write a read-only object.
    pub const READ_ONLY: u32 = 0x0601_0002;
    /// Object does not exist in the object dictionary.
    pub const NO_OBJECT: u32 = 0x0602_0000;
    /// Object cannot be mapped to the PDO.
    pub const NOT_MAPPABLE: u32 = 0x0604_0041;
    /// The number and length of the objects to be mapped would exceed the PDO length.
    pub const PDO_TOO_LONG: u32 = 0x0604_0042;
    /// Data type does not match, length of service parameter does not match.
    pub const LENGTH_MISMATCH: u32 = 0x0607_0010;
    /// Sub-index does not exist.
    pub const NO_SUBINDEX: u32 = 0x0609_0011;
    /// Invalid value for parameter (download only).
    pub const INVALID_VALUE: u32 = 0x0609_0030;
    /// General error.
    pub const GENERAL: u32 = 0x0800_0000;
    /// Data cannot be transferred or stored because of the present device state (e.g. a
    /// mapping written while its PDO is enabled).
    pub const DEVICE_STATE: u32 = 0x0800_0022;
}

/// An object dictionary entry.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Object {
    /// The object index.
    pub index: u16,
    /// The sub-index.
    pub subindex: u8,
}

impl Object {
    /// 0x1016 sub 1, the first consumer heartbeat entry (value: [`ConsumerHeartbeat`]).
    pub const CONSUMER_HEARTBEAT: Self = Self {
        index: 0x1016,
        subindex: 1,
    };
}

/// The value of a consumer heartbeat entry: expect `producer`'s heartbeat at least every
/// `time_ms` milliseconds (0 disables). On the wire: the node id in bits 16..=22, the time in
/// bits 0..=15.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ConsumerHeartbeat {
    /// The node whose heartbeat is expected; `None` for an entry whose node id is 0.
    pub producer: Option<NodeId>,
    /// The longest gap between two heartbeats (ms).
    pub time_ms: u16,
}

impl ConsumerHeartbeat {
    /// The entry's 32-bit value.
    pub const fn to_value(self) -> u32 {
        let node = match self.producer {
            Some(node) => node.get() as u32,
            None => 0,
        };
        node << 16 | self.time_ms as u32
    }

    /// The entry of a 32-bit value (the reserved bits ignored).
    pub fn from_value(value: u32) -> Self {
        Self {
            producer: NodeId::new(((value >> 16) & 0x7F) as u8),
            time_ms: (value & 0xFFFF) as u16,
        }
    }
}

/// An expedited value; its size sets the command specifier.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SdoValue {
    /// 1 byte.
    U8(u8),
    /// 2 bytes, little-endian.
    U16(u16),
    /// 4 bytes, little-endian.
    U32(u32),
}

impl SdoValue {
    /// The value as a number, whatever its size.
    pub const fn get(self) -> u32 {
        match self {
            Self::U8(v) => v as u32,
            Self::U16(v) => v as u32,
            Self::U32(v) => v,
        }
    }

    /// The expedited command specifier `base` with this value's size.
    const fn specifier(self, base: u8) -> u8 {
        base | match self {
            Self::U8(_) => 3 << 2,
            Self::U16(_) => 2 << 2,
            Self::U32(_) => 0,
        }
    }

    /// The four data bytes, zero past the value.
    const fn to_bytes(self) -> [u8; 4] {
        match self {
            Self::U8(v) => [v, 0, 0, 0],
            Self::U16(v) => {
                let [a, b] = v.to_le_bytes();
                [a, b, 0, 0]
            }
            Self::U32(v) => v.to_le_bytes(),
        }
    }

    /// The value of an expedited specifier based on `base`; [`Error::Malformed`] if
    /// `specifier` is not one, or gives an unsupported size (3 bytes).
    fn decode(specifier: u8, base: u8, [d0, d1, d2, d3]: [u8; 4]) -> Result<Self, Error> {
        if specifier & !cs::SIZE != base {
            return Err(Error::Malformed);
        }
        match (specifier & cs::SIZE) >> 2 {
            3 => Ok(Self::U8(d0)),
            2 => Ok(Self::U16(u16::from_le_bytes([d0, d1]))),
            0 => Ok(Self::U32(u32::from_le_bytes([d0, d1, d2, d3]))),
            _ => Err(Error::Malformed),
        }
    }
}

/// A request from the controller (SDO client) to a node.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SdoRequest {
    /// Write `value` to `object`.
    Download {
        /// The entry written.
        object: Object,
        /// The value.
        value: SdoValue,
    },
    /// Read `object`.
    Upload {
        /// The entry read.
        object: Object,
    },
}

impl SdoRequest {
    /// Object 0x1016 sub 1, the first consumer heartbeat entry: expect `producer`'s heartbeat at
    /// least every `time_ms` milliseconds (0 disables).
    pub const fn consumer_heartbeat(producer: NodeId, time_ms: u16) -> Self {
        let entry = ConsumerHeartbeat {
            producer: Some(producer),
            time_ms,
        };
        Self::Download {
            object: Object::CONSUMER_HEARTBEAT,
            value: SdoValue::U32(entry.to_value()),
        }
    }

    /// Object 0x1017: produce a heartbeat every `time_ms` milliseconds (0 disables).
    pub const fn producer_heartbeat(time_ms: u16) -> Self {
        let object = Object {
            index: 0x1017,
            subindex: 0,
        };
        Self::Download {
            object,
            value: SdoValue::U16(time_ms),
        }
    }
}

impl NodeMessage for SdoRequest {
    const FUNCTION: Function = Function::SdoRequest;

    fn decode(frame: &CanFrame) -> Result<Self, Error> {
        let (specifier, object, data) = split(frame)?;
        match specifier {
            cs::UPLOAD => Ok(Self::Upload { object }),
            _ => SdoValue::decode(specifier, cs::DOWNLOAD, data)
                .map(|value| Self::Download { object, value }),
        }
    }

    fn encode(&self) -> (u8, [u8; 8]) {
        match *self {
            Self::Download { object, value } => {
                join(value.specifier(cs::DOWNLOAD), object, value.to_bytes())
            }
            Self::Upload { object } => join(cs::UPLOAD, object, [0; 4]),
        }
    }
}

/// A node's response to an [`SdoRequest`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SdoResponse {
    /// The download to `object` succeeded.
    Downloaded {
        /// The entry written.
        object: Object,
    },
    /// The value read from `object`.
    Uploaded {
        /// The entry read.
        object: Object,
        /// Its value.
        value: SdoValue,
    },
    /// The node aborted the transfer.
    Abort {
        /// The entry concerned.
        object: Object,
        /// The CiA 301 abort code, e.g. 0x0602_0000 "object does not exist".
        code: u32,
    },
}

impl SdoResponse {
    /// The entry the response is about.
    pub const fn object(&self) -> Object {
        match *self {
            Self::Downloaded { object }
            | Self::Uploaded { object, .. }
            | Self::Abort { object, .. } => object,
        }
    }
}

impl NodeMessage for SdoResponse {
    const FUNCTION: Function = Function::SdoResponse;

    fn decode(frame: &CanFrame) -> Result<Self, Error> {
        let (specifier, object, data) = split(frame)?;
        match specifier {
            cs::DOWNLOADED => Ok(Self::Downloaded { object }),
            cs::ABORT => Ok(Self::Abort {
                object,
                code: u32::from_le_bytes(data),
            }),
            _ => SdoValue::decode(specifier, cs::UPLOADED, data)
                .map(|value| Self::Uploaded { object, value }),
        }
    }

    fn encode(&self) -> (u8, [u8; 8]) {
        match *self {
            Self::Downloaded { object } => join(cs::DOWNLOADED, object, [0; 4]),
            Self::Uploaded { object, value } => {
                join(value.specifier(cs::UPLOADED), object, value.to_bytes())
            }
            Self::Abort { object, code } => join(cs::ABORT, object, code.to_le_bytes()),
        }
    }
}

/// Specifier, object and data of an 8-byte SDO frame.
fn split(frame: &CanFrame) -> Result<(u8, Object, [u8; 4]), Error> {
    let [specifier, i0, i1, subindex, data @ ..] = *frame.raw_data();
    if frame.dlc() != 8 {
        return Err(Error::WrongLength);
    }
    Ok((
        specifier,
        Object {
            index: u16::from_le_bytes([i0, i1]),
            subindex,
        },
        data,
    ))
}

/// The frame data for `split`'s parts.
fn join(specifier: u8, object: Object, [d0, d1, d2, d3]: [u8; 4]) -> (u8, [u8; 8]) {
    let [i0, i1] = object.index.to_le_bytes();
    (8, [specifier, i0, i1, object.subindex, d0, d1, d2, d3])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(id: u16, data: &[u8]) -> CanFrame {
        CanFrame::new(id, data).unwrap()
    }

    #[test]
    fn specifiers_by_size() {
        let object = Object {
            index: 0x2000,
            subindex: 2,
        };
        let cases = [
            (SdoValue::U8(0xAB), 0x2F, 0x4F, [0xAB, 0, 0, 0]),
            (SdoValue::U16(0xABCD), 0x2B, 0x4B, [0xCD, 0xAB, 0, 0]),
            (SdoValue::U32(0x0102_0304), 0x23, 0x43, [4, 3, 2, 1]),
        ];
        for (value, download, upload, [d0, d1, d2, d3]) in cases {
            let request = SdoRequest::Download { object, value };
            assert_eq!(
                request.encode(),
                (8, [download, 0x00, 0x20, 2, d0, d1, d2, d3])
            );
            let response = SdoResponse::Uploaded { object, value };
            assert_eq!(
                response.encode(),
                (8, [upload, 0x00, 0x20, 2, d0, d1, d2, d3])
            );
            assert_eq!(
                SdoRequest::decode(&frame(0x601, &request.encode().1)),
                Ok(request)
            );
            assert_eq!(
                SdoResponse::decode(&frame(0x581, &response.encode().1)),
                Ok(response)
            );
        }
    }

    #[test]
    fn rejects_unsupported_frames() {
        let request = |data: &[u8]| SdoRequest::decode(&frame(0x601, data));
        assert_eq!(request(&[0x40, 0, 0x10, 0]), Err(Error::WrongLength));
        assert_eq!(
            request(&[0x27, 0, 0x10, 0, 1, 2, 3, 0]),
            Err(Error::Malformed)
        ); // 3 bytes
        assert_eq!(
            request(&[0x22, 0, 0x10, 0, 1, 2, 3, 4]),
            Err(Error::Malformed)
        ); // no size
        assert_eq!(
            request(&[0x21, 0, 0x10, 0, 0, 0, 0, 0]),
            Err(Error::Malformed)
        ); // segmented
        let response = |data: &[u8]| SdoResponse::decode(&frame(0x581, data));
        assert_eq!(
            response(&[0x41, 0, 0x10, 0, 4, 0, 0, 0]),
            Err(Error::Malformed)
        );
        assert_eq!(
            response(&[0x23, 0, 0x10, 0, 4, 0, 0, 0]),
            Err(Error::Malformed)
        );
    }

    #[test]
    fn consumer_heartbeat_entry() {
        // The manager's entry: controller node 127, 300 ms.
        let entry = ConsumerHeartbeat::from_value(0x007F_012C);
        assert_eq!(entry.producer.map(NodeId::get), Some(127));
        assert_eq!(entry.time_ms, 300);
        assert_eq!(entry.to_value(), 0x007F_012C);
        let disabled = ConsumerHeartbeat::from_value(0);
        assert_eq!((disabled.producer, disabled.time_ms), (None, 0));
        assert_eq!(disabled.to_value(), 0);
    }

    #[test]
    fn abort_code() {
        let abort = SdoResponse::decode(&frame(0x581, &[0x80, 0x16, 0x10, 1, 0, 0, 2, 6]));
        let object = Object {
            index: 0x1016,
            subindex: 1,
        };
        assert_eq!(
            abort,
            Ok(SdoResponse::Abort {
                object,
                code: 0x0602_0000
            })
        );
    }
}
