//! CAN frames: the Elmo SimplIQ binary interpreter and the CANopen services around it
//! (spec §6.3, §6.7).
//!
//! Every frame uses a standard 11-bit identifier. Except for NMT commands (COB-ID 0) and SYNC
//! (0x080), the COB-ID is a [`Function`] code plus a [`NodeId`]; the messages addressed that
//! way implement [`NodeMessage`], which turns them into frames and back. [`Incoming::classify`]
//! sorts what a drive sends to the controller.
//!
//! Two streaming schedules use them: the interpreter schedule (RPDO2/TPDO2, [`interpreter`])
//! and the PDO schedule ([`SyncObject`], [`PtPoint`] in RPDO3, [`PtFeedback`] in TPDO3, mapped
//! at start-up by the SDO writes of [`streaming_mapping`], and [`TimeStamp`] to lock the drives'
//! clocks).
//!
//! ```
//! use armgate_protocol::can::interpreter::{Index, Mnemonic, Reply, Request, Value};
//! use armgate_protocol::can::{CanFrame, Incoming, NodeId, NodeMessage};
//!
//! let node = NodeId::new(101).unwrap();
//! let query = Request::Query { command: Mnemonic::PX, index: Index::ZERO }.to_frame(node);
//! assert_eq!((query.id(), query.data()), (0x365, &b"PX\0\0"[..]));
//!
//! let answer = CanFrame::new(0x2E5, &[b'P', b'X', 0, 0, 0x39, 0x30, 0, 0]).unwrap();
//! let Incoming::Interpreter { node: from, reply } = Incoming::classify(&answer) else { panic!() };
//! assert_eq!(from, node);
//! assert_eq!(reply, Reply::Value { command: Mnemonic::PX, index: Index::ZERO, value: Value::Int(12345) });
//! ```

mod cob;
mod emcy;
mod error;
mod frame;
mod incoming;
pub mod interpreter;
mod mapping;
mod nmt;
pub mod pdo;
mod sdo;
mod sync;
mod time_stamp;

pub use cob::{Function, NodeId, NodeMessage};
pub use emcy::Emcy;
pub use error::Error;
pub use frame::{CanFrame, MAX_DLC, MAX_ID, bits_on_wire, exact_bits_on_wire};
pub use incoming::Incoming;
pub use mapping::{
    ASYNCHRONOUS, MAPPING_STEPS, MappingRefusal, MappingStep, PDO_DISABLED, PDO_NO_RTR,
    RPDO3_COMMUNICATION, RPDO3_MAPPING, SYNCHRONOUS, TPDO3_COMMUNICATION, TPDO3_MAPPING,
    group_id_step, mapping_entry, streaming_mapping,
};
pub use nmt::{Heartbeat, Nmt, NmtCommand, NmtState};
pub use pdo::{PtFeedback, PtPoint};
pub use sdo::abort as sdo_abort;
pub use sdo::{ConsumerHeartbeat, Object, SdoRequest, SdoResponse, SdoValue};
pub use sync::{SYNC_ID, SyncObject};
pub use time_stamp::{TIME_STAMP_ID, TimeStamp};
