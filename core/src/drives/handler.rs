//! The drive manager as the client's command handler sees it (ON, OF, RC, TM, faults).

use armgate_protocol::client::{DriveStatus, Severity, Text};

use super::manager::DriveManager;
use super::state::DriveState;
use crate::command::Drives;
use crate::kinematics::Joints;
use crate::motion::Refusal;

/// `start` and `stop` only begin the transition: a start that later fails shows as a fault
/// (its `ER3x` text), and motion stays refused until [`Drives::is_operational`].
impl Drives for DriveManager {
    fn start(&mut self) -> bool {
        DriveManager::start(self).is_ok()
    }

    fn stop(&mut self) -> bool {
        DriveManager::stop(self).is_ok()
    }

    fn recalibrate(&mut self, q: &[f64]) -> Result<(), Refusal> {
        DriveManager::recalibrate(self, q)
    }

    fn temperatures(&self) -> Joints {
        DriveManager::temperatures(self)
    }

    fn is_operational(&self) -> bool {
        DriveManager::is_operational(self)
    }

    fn status(&self) -> DriveStatus {
        match self.state() {
            DriveState::Idle | DriveState::Stopped => DriveStatus::Off,
            DriveState::Starting => DriveStatus::Starting,
            DriveState::Operational => DriveStatus::Running,
            DriveState::Stopping => DriveStatus::Stopping,
            DriveState::Faulted => DriveStatus::Faulted,
        }
    }

    fn fault_code(&self) -> Option<u8> {
        DriveManager::fault(self).map(|fault| fault.code())
    }

    fn fault(&self) -> Option<Text> {
        DriveManager::fault(self).map(|fault| fault.text())
    }

    fn has_fault(&self) -> bool {
        DriveManager::fault(self).is_some()
    }

    /// `WN39` with the refusal's text: the PDO mapping was refused and the interpreter
    /// schedule runs instead.
    fn notice(&self) -> Option<Text> {
        DriveManager::fallback(self).map(|refusal| refusal.text_as(Severity::Warning))
    }
}
