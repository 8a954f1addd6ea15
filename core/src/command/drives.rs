//! What the command handler needs from the drives.

use armgate_protocol::client::{DriveStatus, Text};

use crate::drives::LifecycleError;
use crate::kinematics::Joints;
use crate::motion::Refusal;

/// The drive side of the arm as the client commands see it (ON, OF, RC, TM): the CAN drive
/// manager on the board, or a simulated arm.
pub trait Drives {
    /// Starts the drives (motor on, set-point streaming); [`LifecycleError::Running`] if they
    /// cannot start now because they already run. Starting may take several cycles: a drive that then fails to
    /// answer shows as a [`fault`](Self::fault), and motion stays refused until
    /// [`is_operational`](Self::is_operational).
    fn start(&mut self) -> Result<(), LifecycleError>;
    /// Stops the drives; [`LifecycleError::NotRunning`] if they were not running.
    fn stop(&mut self) -> Result<(), LifecycleError>;
    /// Declares the current joint positions to be `q` (one value per joint). Refused with
    /// [`Refusal::Busy`] while set-points still move the joints (or the drives start or
    /// stop), [`Refusal::NotReady`] before every position has been read.
    fn recalibrate(&mut self, q: &[f64]) -> Result<(), Refusal>;
    /// Drive temperatures (°C), one per joint; −100 until a drive has reported.
    fn temperatures(&self) -> Joints;
    /// True while set-points reach the joints; motion requests are refused otherwise.
    fn is_operational(&self) -> bool {
        self.status() == DriveStatus::Running
    }
    /// The drives' state, as the status request reports it.
    fn status(&self) -> DriveStatus;
    /// The current fault's `ER` code (30..=39), if any.
    fn fault_code(&self) -> Option<u8>;
    /// The text of the current drive fault, if any (sent once to the client when it appears).
    fn fault(&self) -> Option<Text>;
    /// Whether there is a drive fault: what the handler asks every tick, so an implementation
    /// that formats the [`fault`](Self::fault) text should answer it without formatting.
    fn has_fault(&self) -> bool {
        self.fault().is_some()
    }
    /// A warning about the drives that lasts until the next start (the PDO schedule's fallback
    /// to the interpreter schedule), sent once to the client when it appears.
    fn notice(&self) -> Option<Text> {
        None
    }
}
