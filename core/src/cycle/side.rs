//! The drive side of a tick.

use crate::command::Drives;
use crate::kinematics::Joints;

/// The drives as the cycle runs them: the [`Drives`] the client's requests act on, plus the
/// two halves of a tick around the control step.
pub trait DriveSide: Drives {
    /// Before the control step, at the tick's time `now` (s): takes what the drives reported.
    /// False if a simulated bus stalled (counted as a tick error; the drive manager's timeouts
    /// then fault).
    fn receive(&mut self, now: f64) -> bool;
    /// The measured joints the step starts from.
    fn measured(&self) -> Joints;
    /// After the step: sends `command` (`None`: hold), `elapsed` (s) after the previous tick.
    fn transmit(&mut self, now: f64, elapsed: f64, command: Option<&Joints>);
}
