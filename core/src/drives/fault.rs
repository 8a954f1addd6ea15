//! Why the drives were stopped.

use armgate_protocol::can::interpreter::Mnemonic;
use armgate_protocol::can::{Emcy, Object};

use super::settings::POSITION_MODE;

/// A drive or bus fault. Every fault stops the arm (the drives hold the last commanded
/// position where they still can) and refuses motion until the next start (ON).
///
/// `joint` is the 0-based joint index; the client texts number joints from 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DriveFault {
    /// `ER30`: a drive did not answer within the reply timeout (the seed only warned, §9 item 34).
    NotAnswering {
        /// The joint.
        joint: usize,
    },
    /// `ER31`: a drive answered a command with the error bit set (§6.7).
    ErrorReply {
        /// The joint.
        joint: usize,
        /// The command refused.
        command: Mnemonic,
        /// The drive's error code (see `EC` in the SimplIQ command reference).
        code: u8,
    },
    /// `ER32`: an emergency message other than those with their own fault.
    Emergency {
        /// The joint.
        joint: usize,
        /// The message.
        emcy: Emcy,
    },
    /// `ER33`: a drive ran out of PT points.
    Underflow {
        /// The joint.
        joint: usize,
    },
    /// `ER34`: a drive stopped taking PT points, or a point overwrote one not yet executed.
    Overrun {
        /// The joint.
        joint: usize,
    },
    /// `ER35`: the controller cannot send.
    Bus(BusFault),
    /// `ER36`: a drive missed the controller's heartbeat and stopped by itself.
    HeartbeatLost {
        /// The joint.
        joint: usize,
    },
    /// `ER37`: a drive is not in the configured unit mode, even after it was asked to change.
    WrongUnitMode {
        /// The joint.
        joint: usize,
        /// The unit mode the drive reports.
        found: i32,
    },
    /// `ER38`: a drive answered `BG` with a value other than 0.
    BeginRefused {
        /// The joint.
        joint: usize,
        /// The value answered.
        value: i32,
    },
    /// `ER39`: a drive refused the heartbeat configuration (SDO abort).
    SdoAbort {
        /// The joint.
        joint: usize,
        /// The CiA 301 abort code.
        code: u32,
    },
    /// `ER39`: a drive refused the PDO schedule's mapping: it aborted the write to `object`
    /// (`code`), or `object` read back another value (`code` `None`).
    MappingRefused {
        /// The joint.
        joint: usize,
        /// The object refused.
        object: Object,
        /// The CiA 301 abort code, if the drive aborted.
        code: Option<u32>,
    },
    /// `ER30`: PDO schedule: a drive's transmit PDO was missing for this many SYNCs in a row.
    NoFeedback {
        /// The joint.
        joint: usize,
        /// SYNCs without it.
        cycles: u32,
    },
    /// `ER35`: PDO schedule: the SYNC went out this late (µs after its due time): the control
    /// cycle missed its period, and the drives' points with it.
    LateSync {
        /// How late.
        late_us: u32,
    },
}

/// Why the controller cannot send.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BusFault {
    /// The CAN controller went bus-off.
    BusOff,
    /// The transmit queue stayed full.
    QueueFull,
}

impl DriveFault {
    /// The two-digit `ER` code.
    pub const fn code(&self) -> u8 {
        match self {
            Self::NotAnswering { .. } | Self::NoFeedback { .. } => 30,
            Self::ErrorReply { .. } => 31,
            Self::Emergency { .. } => 32,
            Self::Underflow { .. } => 33,
            Self::Overrun { .. } => 34,
            Self::Bus(_) | Self::LateSync { .. } => 35,
            Self::HeartbeatLost { .. } => 36,
            Self::WrongUnitMode { .. } => 37,
            Self::BeginRefused { .. } => 38,
            Self::SdoAbort { .. } | Self::MappingRefused { .. } => 39,
        }
    }
}

/// The fault's description, e.g. `J3 drive not answering`: the body of the client's `ER3x`
/// text (`crate::cycle::can_drives` puts the code before it).
impl core::fmt::Display for DriveFault {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let mut text = |body: core::fmt::Arguments<'_>| f.write_fmt(body);
        match *self {
            Self::NotAnswering { joint } => {
                text(format_args!("J{} drive not answering", joint + 1))
            }
            Self::ErrorReply {
                joint,
                command,
                code,
            } => {
                let [c0, c1] = command.chars();
                let (c0, c1) = (char::from(c0), char::from(c1));
                text(format_args!("J{} {c0}{c1} error code {code}", joint + 1))
            }
            Self::Emergency { joint, emcy } => {
                let [elmo, ..] = emcy.manufacturer;
                text(format_args!(
                    "J{} EMCY {:04X} {elmo:02X}",
                    joint + 1,
                    emcy.code
                ))
            }
            Self::Underflow { joint } => text(format_args!("J{} PT buffer underflow", joint + 1)),
            Self::Overrun { joint } => text(format_args!("J{} PT buffer overrun", joint + 1)),
            Self::Bus(BusFault::BusOff) => text(format_args!("CAN bus off")),
            Self::Bus(BusFault::QueueFull) => text(format_args!("CAN send queue full")),
            Self::HeartbeatLost { joint } => {
                text(format_args!("J{} lost ctrl heartbeat", joint + 1))
            }
            Self::WrongUnitMode { joint, found } => text(format_args!(
                "J{} unit mode {found} not {POSITION_MODE}",
                joint + 1
            )),
            Self::BeginRefused { joint, value } => {
                text(format_args!("J{} did not begin ({value})", joint + 1))
            }
            Self::SdoAbort { joint, code } => {
                text(format_args!("J{} SDO abort {code:08X}", joint + 1))
            }
            Self::MappingRefused {
                joint,
                object,
                code,
            } => {
                let (index, sub) = (object.index, object.subindex);
                match code {
                    Some(code) => text(format_args!(
                        "J{} map {index:04X}:{sub:02X} {code:08X}",
                        joint + 1
                    )),
                    None => text(format_args!(
                        "J{} map {index:04X}:{sub:02X} read back",
                        joint + 1
                    )),
                }
            }
            Self::NoFeedback { joint, cycles } => {
                text(format_args!("J{} no TPDO for {cycles} cycles", joint + 1))
            }
            Self::LateSync { late_us } => text(format_args!("SYNC late by {late_us} us")),
        }
    }
}
