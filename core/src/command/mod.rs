//! Command handling: client requests (the 31-byte protocol) mapped onto the [`Controller`],
//! with the semantics the seed intended (spec §2.5, §2.8) and its defects fixed (§9), and the
//! relay of unsolicited warnings (§2.6); who is talking (the clients, the one that holds the
//! arm, where notices go); and the allow-list of who may send requests.
//!
//! [`Controller`]: crate::motion::Controller

mod allow;
mod banks;
mod drives;
mod handler;
mod ik;
mod redundancy;
mod relay;
mod session;
mod status;

pub use allow::{Network, NetworkError};
pub use drives::Drives;
pub use handler::{CommandHandler, Slice};
pub use relay::{NOTICE_CAPACITY, NOTICE_INTERVAL, NoticeRelay};
pub use session::{CLIENTS, Class, Session};
pub use status::Status;
// The wire's state enums, which the drives and the status snapshot report in.
pub use armgate_protocol::client::{DriveStatus, Motion};
