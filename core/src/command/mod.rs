//! Command handling: client requests (the 31-byte protocol) mapped onto the [`Controller`],
//! with the semantics the seed intended (spec §2.5, §2.8) and its defects fixed (§9), and the
//! relay of unsolicited warnings (§2.6); and the allow-list of who may send requests.
//!
//! [`Controller`]: crate::motion::Controller

mod allow;
mod banks;
mod drives;
mod handler;
mod relay;
mod simulated;

pub use allow::{Network, NetworkError};
pub use drives::Drives;
pub use handler::CommandHandler;
pub use relay::{NOTICE_CAPACITY, NOTICE_INTERVAL, NoticeRelay};
pub use simulated::{ArmModel, SimulatedDrives};
