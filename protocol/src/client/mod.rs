//! The 31-byte client messages (spec §2).
//!
//! A controller answering one datagram:
//!
//! ```
//! use armgate_protocol::client::{Message, MESSAGE_LEN, Notice, Reply, Request};
//!
//! fn answer(datagram: &[u8]) -> [u8; MESSAGE_LEN] {
//!     match Message::new_checked(datagram).and_then(|m| Request::parse(&m)) {
//!         Ok(request) => Reply::null(request.command).to_bytes(),
//!         Err(error) => Notice::from(error).text().to_bytes(),
//!     }
//! }
//!
//! assert_eq!(&answer(b"BG")[..24], b"ER01 Msg BG undersized.\0");
//! assert_eq!(&answer(&[b'X'; 31])[..27], b"ER00 Cmd XX not understood\0");
//! let mut begin = [0; MESSAGE_LEN];
//! begin[..2].copy_from_slice(b"BG");
//! assert_eq!(answer(&begin)[..], [&b"GB"[..], &[0; 29]].concat());
//! ```
//!
//! * [`Message`]: the length-checked view of a datagram, with field accessors.
//! * [`Command`]: the request command pairs.
//! * [`Request`] and [`Reply`]: command, seven floats and the index.
//! * [`Text`]: the `ER`/`WN` text messages; [`Notice`]: the fixed texts, with their typed
//!   reasons ([`Rejection`], [`WorkspaceReason`], [`JointBound`], [`Hit`]), written and read back
//!   ([`Notice::parse`], [`NoticeError`]); [`Header`]: the parts every text shares, any
//!   controller's (code, named command, detail; [`DRIVE_FAULT_CODES`]).
//! * [`StatusReport`], [`RobotName`], [`CauseReport`], [`SessionReport`] and
//!   [`NearestReport`]: the replies to the status request `SQ` (indices 0, 1, 2, 3, 7).
//! * [`Error`]: why a datagram is not a request (or reply).
//! * [`branch`] and [`redundancy`]: the configuration of a closed-form IK solution (`KG`,
//!   `KS`, `KR`).
//! * [`banks`]: how seven floats carry up to eight joints; [`Mode`]: the control modes of `CM`;
//!   [`UNKNOWN_TEMPERATURE`], [`NO_JOINT_TEMPERATURE`]: the sentinels of `TM`.
//! * [`BlendTolerance`]: the via points' blend tolerances, `VT` and `jT`.
//! * [`Twist`] and [`JointRates`]: the velocity-streaming requests `TW` and `jW`.
//! * [`signed`]: the signed form of every datagram (a key, a link id, a timestamp, a tag).

pub mod banks;
mod blend;
pub mod branch;
mod command;
mod error;
mod header;
mod hit;
mod message;
mod mode;
mod nearest;
mod notice;
mod orientation;
mod reason;
pub mod redundancy;
mod reply;
mod request;
mod session;
pub mod signed;
mod status;
mod stop;
mod temperature;
mod text;
#[cfg(test)]
mod vectors;
mod velocity;
mod words;

pub use blend::{BlendTolerance, ViaKind};
pub use command::Command;
pub use error::{DecodeError, Error};
pub use header::{DRIVE_FAULT_CODES, Header, NoticeError};
pub use hit::{Hit, Obstacle};
pub use message::{MESSAGE_LEN, MIN_LEN, Message, VALUES};
pub use mode::Mode;
pub use nearest::{NEAREST_INDEX, NearestReport, OBSTACLE_KINDS};
pub use notice::Notice;
pub use orientation::{Quaternion, rpy};
pub use reason::{
    DriveStatus, Hold, JointBound, Lag, MAX_LAG_MILLI, PathPoint, Rejection, WorkspaceReason,
};
pub use reply::Reply;
pub use request::Request;
pub use session::{Holder, SESSION_INDEX, SessionReport};
pub use status::{Motion, NAME_INDEX, NAME_LEN, RobotName, STATUS_INDEX, StatusReport};
pub use stop::{CAUSE_INDEX, CauseReport, StopCause};
pub use temperature::{NO_JOINT_TEMPERATURE, UNKNOWN_TEMPERATURE};
pub use text::{Severity, TEXT_CAPACITY, Text};
pub use velocity::{JointRates, TOOL_FRAME, Twist, TwistFrame, VelocityError};
