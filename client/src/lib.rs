//! armgate's client: talk to an armgate controller over its 31-byte UDP protocol
//! (docs/protocol.md), from Rust or from the `armgate` command line.
//!
//! ```no_run
//! use armgate_client::{Client, Mode, Pose, WaitOptions};
//!
//! # fn main() -> Result<(), armgate_client::ClientError> {
//! let mut arm = Client::connect("127.0.0.1:7031")?;
//! arm.set_mode(Mode::Cartesian)?;
//! arm.goal_rpy([0.5, 0.2, 0.1], [0.0, 0.0, 0.0], 5.0)?;
//! arm.begin()?;
//! let goal = Pose::from_xyz_rpy([0.5, 0.2, 0.1], [0.0, 0.0, 0.0]);
//! let pose = arm.wait_until_pose(&goal, &WaitOptions::default(), |p| {
//!     eprintln!("{:.1} mm to go", p.distance * 1e3);
//! })?;
//! println!("arrived at {:?}", pose.xyz);
//! for notice in arm.take_notices() {
//!     eprintln!("{notice}"); // e.g. "WN12 Joint limit."
//! }
//! # Ok(())
//! # }
//! ```
//!
//! * [`Client`]: requests with timeout and retries, reply matching ([`matching`]), the queue of
//!   unsolicited notices, and one typed method per command (`pose`, `joints`, `goal_rpy`,
//!   `begin`, `joint_goal`, `via_joint`, ...; joint requests follow the bank rule, [`banks`]).
//! * [`wait`]: polling until a pose or joint target is reached; a wait that does not arrive
//!   sends `ST` and says so, and one the controller stopped says why and who
//!   ([`ended`], [`ClientError::Stopped`]).
//! * [`exit`]: the `armgate` tool's exit statuses, one table for every subcommand.
//! * [`velocity`]: twist and joint-rate streaming (`TW`, `jW`), [`VelocityStreamer`].
//! * [`runfile`]: TOML via-point sequences.
//! * [`status`]: the status request `SQ` (mode, drives, joint count, robot name);
//!   [`Client::start_drives`] and [`Client::wait_motion_ended`] poll it.
//! * [`Signer`]: signed requests and checked answers (a key file, a link id).
//! * [`cli`]: the `armgate` tool; [`teleop`]: its keyboard client; [`plot`]: `armgate plot`.

pub mod banks;
pub mod cli;
mod client;
mod commands;
mod drives;
pub mod ended;
mod error;
pub mod exit;
#[cfg(test)]
mod fake;
mod hints;
mod ik;
pub mod interrupt;
pub mod matching;
pub mod plot;
mod pose;
pub mod runfile;
mod signer;
pub mod status;
pub mod teleop;
pub mod tools;
pub mod velocity;
pub mod wait;

pub use armgate_protocol::client::redundancy::Redundancy;
pub use armgate_protocol::client::{Command, Reply, Request, Text, TwistFrame};
pub use client::{
    Client, ClientConfig, DEFAULT_ADDR, DEFAULT_NOTICE_CAPACITY, DEFAULT_RETRIES, DEFAULT_TIMEOUT,
    RawReply,
};
pub use commands::NO_READING;
pub use drives::DrivesOn;
pub use ended::{EndStop, StopPolicy, Stopper};
pub use error::ClientError;
pub use ik::IkSolution;
pub use pose::{Mode, Pose, Quaternion, next_mode};
pub use runfile::{RunFile, RunFileError};
pub use signer::Signer;
pub use status::{DriveStatus, Motion, Status};
pub use velocity::{StreamEvent, Streamed, Velocity, VelocityStreamer};
pub use wait::{Progress, WaitOptions};
