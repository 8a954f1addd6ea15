//! The drive manager as the client's command handler sees it (ON, OF, RC, TM, faults).

use armgate_protocol::client::Text;

use super::manager::DriveManager;
use crate::command::Drives;
use crate::kinematics::Joints;

/// `start` and `stop` only begin the transition: a start that later fails shows as a fault
/// (its `ER3x` text), and motion stays refused until [`Drives::is_operational`].
impl Drives for DriveManager {
    fn start(&mut self) -> bool {
        DriveManager::start(self).is_ok()
    }

    fn stop(&mut self) -> bool {
        DriveManager::stop(self).is_ok()
    }

    fn recalibrate(&mut self, q: &[f64]) -> bool {
        DriveManager::recalibrate(self, q).is_ok()
    }

    fn temperatures(&self) -> Joints {
        DriveManager::temperatures(self)
    }

    fn is_operational(&self) -> bool {
        DriveManager::is_operational(self)
    }

    fn fault(&self) -> Option<Text> {
        DriveManager::fault(self).map(|fault| fault.text())
    }

    fn has_fault(&self) -> bool {
        DriveManager::fault(self).is_some()
    }
}
