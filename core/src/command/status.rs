//! What the controller is doing, in one snapshot: the `SQ` reply, and a shell's status line.

use armgate_protocol::client::{DriveStatus, Motion, StatusReport};

use crate::motion::Mode;

/// A snapshot of the controller's state ([`CommandHandler::status`]); the status request
/// `SQ` sends it as a [`StatusReport`].
///
/// [`CommandHandler::status`]: super::CommandHandler::status
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Status {
    /// The control mode.
    pub mode: Mode,
    /// The drives' state.
    pub drives: DriveStatus,
    /// The current drive fault's `ER` code (30..=39), if any.
    pub fault: Option<u8>,
    /// The number of joints.
    pub joints: usize,
    /// What the arm is doing.
    pub motion: Motion,
    /// Requests refused (answered with an `ER` text) since the start.
    pub refused: u32,
    /// Time of the last control tick (s since the controller started).
    pub uptime: f64,
}

impl Status {
    /// The wire form (`QS`, index 0).
    pub fn report(&self) -> StatusReport {
        StatusReport {
            mode: self.mode,
            drives: self.drives,
            fault: self.fault.unwrap_or(0),
            joints: u8::try_from(self.joints).unwrap_or(u8::MAX),
            motion: self.motion,
            refused: self.refused,
            uptime: self.uptime as f32,
        }
    }
}
