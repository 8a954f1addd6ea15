//! What a drive's emergency message means (Elmo CANopen DS 301 Implementation Guide
//! MAN-CAN301IG, Table 13-4 "PVT CAN emergency messages"; CiA 301 for the heartbeat code).
//!
//! Elmo reports its own events with the EMCY code 0xFF00 and error register 0x81; byte 3 is the
//! Elmo code and bytes 4–5 and 6–7 are two 16-bit data fields.

use armgate_protocol::can::Emcy;

/// The EMCY code of Elmo's manufacturer-specific emergencies.
const ELMO: u16 = 0xFF00;
/// The error register Elmo sends with them.
const ELMO_REGISTER: u8 = 0x81;
/// CiA 301: life guard or heartbeat error.
const HEARTBEAT: u16 = 0x8130;
/// Error register bits 0 (generic) and 4 (communication).
const COMMUNICATION_REGISTER: u8 = 0x11;

/// Elmo codes in byte 3.
mod elmo {
    /// More points programmed than the queue holds: an unexecuted point was overwritten.
    pub const QUEUE_FULL: u8 = 0x34;
    /// The PT/PVT mode ended and the motor was stopped.
    pub const MOTION_TERMINATED: u8 = 0x08;
    /// A received CAN message was lost (the interpreter's queue overflowed).
    pub const MESSAGE_LOST: u8 = 0x09;
    /// Fewer unexecuted points than `MP[5]` remain.
    pub const QUEUE_LOW: u8 = 0x56;
    /// A point arrived by PDO while the write pointer `MP[6]` is outside `MP[1]..=MP[2]`.
    pub const WRITE_POINTER_OUT_OF_RANGE: u8 = 0x5B;
    /// Motion needs points from a PDO that is not mapped ("PDO 0x3xx is not mapped").
    pub const PDO_NOT_MAPPED: u8 = 0x5C;
}

/// `MotionTerminated::reason`: the read pointer reached the write pointer (buffer underflow).
pub const REASON_UNDERFLOW: u16 = 3;

/// A drive emergency, decoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DriveEmergency {
    /// EMCY code 0: a previous error has cleared.
    ErrorReset,
    /// Code 0x8380, register 0x81: what the seed treated as a digital Hall sensor error and
    /// ignored (spec §6.7); kept as a harmless warning.
    DigitalHall,
    /// Fewer unexecuted PT points than `MP[5]` remain (a warning: the motion goes on).
    QueueLow {
        /// The drive's write pointer.
        write: u16,
        /// The drive's read pointer.
        read: u16,
    },
    /// A PT point was written over a point not yet executed; the write was refused.
    QueueFull {
        /// The table index that could not be written.
        index: u16,
    },
    /// PT motion ended and the motor stopped where it was.
    MotionTerminated {
        /// The drive's write pointer.
        write: u16,
        /// Why: 1 end of a non-cyclic table, 2 bad segment time, [`REASON_UNDERFLOW`].
        reason: u16,
    },
    /// The drive lost a received CAN message.
    MessageLost,
    /// A PT point arrived by PDO while the write pointer was outside the table.
    WritePointerOutOfRange {
        /// The drive's write pointer.
        write: u16,
    },
    /// PT points were to come by PDO, but the PDO is not mapped.
    PdoNotMapped {
        /// The PDO's COB-ID (ASSUMED: Elmo's first data field; the manual names only the
        /// PDO in its text).
        cob_id: u16,
    },
    /// The drive stopped receiving the controller's heartbeat in time.
    HeartbeatLost,
    /// Anything else.
    Other(Emcy),
}

impl DriveEmergency {
    /// The meaning of `emcy`.
    pub fn decode(emcy: &Emcy) -> Self {
        let [code, a0, a1, b0, b1] = emcy.manufacturer;
        let (field1, field2) = (u16::from_le_bytes([a0, a1]), u16::from_le_bytes([b0, b1]));
        match (emcy.code, code) {
            (0, _) => Self::ErrorReset,
            _ if emcy.is_digital_hall() => Self::DigitalHall,
            (HEARTBEAT, _) => Self::HeartbeatLost,
            (ELMO, elmo::QUEUE_LOW) => Self::QueueLow {
                write: field1,
                read: field2,
            },
            (ELMO, elmo::QUEUE_FULL) => Self::QueueFull { index: field1 },
            (ELMO, elmo::MOTION_TERMINATED) => Self::MotionTerminated {
                write: field1,
                reason: field2,
            },
            (ELMO, elmo::MESSAGE_LOST) => Self::MessageLost,
            (ELMO, elmo::WRITE_POINTER_OUT_OF_RANGE) => {
                Self::WritePointerOutOfRange { write: field1 }
            }
            (ELMO, elmo::PDO_NOT_MAPPED) => Self::PdoNotMapped { cob_id: field1 },
            _ => Self::Other(*emcy),
        }
    }

    /// The emergency message a drive sends for this event.
    pub fn encode(&self) -> Emcy {
        let elmo = |code: u8, field1: u16, field2: u16| {
            let [a0, a1] = field1.to_le_bytes();
            let [b0, b1] = field2.to_le_bytes();
            Emcy {
                code: ELMO,
                register: ELMO_REGISTER,
                manufacturer: [code, a0, a1, b0, b1],
            }
        };
        match *self {
            Self::ErrorReset => Emcy {
                code: 0,
                register: 0,
                manufacturer: [0; 5],
            },
            Self::DigitalHall => Emcy {
                code: 0x8380,
                register: 0x81,
                manufacturer: [0; 5],
            },
            Self::QueueLow { write, read } => elmo(elmo::QUEUE_LOW, write, read),
            Self::QueueFull { index } => elmo(elmo::QUEUE_FULL, index, 0),
            Self::MotionTerminated { write, reason } => {
                elmo(elmo::MOTION_TERMINATED, write, reason)
            }
            Self::MessageLost => elmo(elmo::MESSAGE_LOST, 0, 0),
            Self::WritePointerOutOfRange { write } => {
                elmo(elmo::WRITE_POINTER_OUT_OF_RANGE, write, 0)
            }
            Self::PdoNotMapped { cob_id } => elmo(elmo::PDO_NOT_MAPPED, cob_id, 0),
            Self::HeartbeatLost => Emcy {
                code: HEARTBEAT,
                register: COMMUNICATION_REGISTER,
                manufacturer: [0; 5],
            },
            Self::Other(emcy) => emcy,
        }
    }
}
