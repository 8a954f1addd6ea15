//! What the command handler needs from the drives.

use armgate_protocol::client::Text;

use crate::kinematics::Joints;

/// The drive side of the arm as the client commands see it (ON, OF, RC, TM): the CAN drive
/// manager on the board, or a simulated arm.
pub trait Drives {
    /// Starts the drives (motor on, set-point streaming); false if they cannot start now, e.g.
    /// because they already run. Starting may take several cycles: a drive that then fails to
    /// answer shows as a [`fault`](Self::fault), and motion stays refused until
    /// [`is_operational`](Self::is_operational).
    fn start(&mut self) -> bool;
    /// Stops the drives; false if they were not running.
    fn stop(&mut self) -> bool;
    /// Declares the current joint positions to be `q` (one value per joint); false if refused.
    fn recalibrate(&mut self, q: &[f64]) -> bool;
    /// Drive temperatures (°C), one per joint; −100 until a drive has reported.
    fn temperatures(&self) -> Joints;
    /// True while set-points reach the joints; motion requests are refused otherwise.
    fn is_operational(&self) -> bool;
    /// The text of the current drive fault, if any (sent once to the client when it appears).
    fn fault(&self) -> Option<Text>;
    /// Whether there is a drive fault: what the handler asks every tick, so an implementation
    /// that formats the [`fault`](Self::fault) text should answer it without formatting.
    fn has_fault(&self) -> bool {
        self.fault().is_some()
    }
}
