//! The CANopen drive manager on its bus, as one [`DriveSide`].

use armgate_protocol::client::{DriveStatus, Text};

use super::DriveSide;
use crate::command::Drives;
use crate::config::ValidRobot;
use crate::drives::{CanBus, DriveManager, DriveSettings, SetupError};
use crate::kinematics::Joints;
use crate::motion::Refusal;

/// The drive manager and the bus it talks through.
#[derive(Clone, Debug)]
pub struct CanDrives<B> {
    manager: DriveManager,
    bus: B,
}

impl<B: CanBus> CanDrives<B> {
    /// The drives of `config` on `bus`, started (the seed auto-started its robot component;
    /// the start runs over the next ticks).
    pub fn started(
        config: &ValidRobot,
        settings: &DriveSettings,
        bus: B,
    ) -> Result<Self, SetupError> {
        let mut drives = Self::idle(config, settings, bus)?;
        // A fresh manager is idle: starting it cannot be refused.
        let _ = drives.manager.start();
        Ok(drives)
    }

    /// The same, idle until the client's `ON` (or [`manager_mut`](Self::manager_mut)`.start()`).
    pub fn idle(config: &ValidRobot, settings: &DriveSettings, bus: B) -> Result<Self, SetupError> {
        Ok(Self {
            manager: DriveManager::new(config, settings)?,
            bus,
        })
    }

    /// The drive manager.
    pub fn manager(&self) -> &DriveManager {
        &self.manager
    }

    /// The drive manager, mutable (test rigs and benches).
    pub fn manager_mut(&mut self) -> &mut DriveManager {
        &mut self.manager
    }

    /// The drive manager and the bus at once, mutable (tests that step the manager by hand).
    pub fn split_mut(&mut self) -> (&mut DriveManager, &mut B) {
        (&mut self.manager, &mut self.bus)
    }

    /// The bus.
    pub fn bus(&self) -> &B {
        &self.bus
    }

    /// The bus, mutable.
    pub fn bus_mut(&mut self) -> &mut B {
        &mut self.bus
    }
}

/// `ON` also asks the bus to leave bus-off: the policy of docs/architecture.md.
impl<B: CanBus> Drives for CanDrives<B> {
    fn start(&mut self) -> bool {
        if self.manager.start().is_err() {
            return false;
        }
        self.bus.recover();
        true
    }

    fn stop(&mut self) -> bool {
        Drives::stop(&mut self.manager)
    }

    fn recalibrate(&mut self, q: &[f64]) -> Result<(), Refusal> {
        Drives::recalibrate(&mut self.manager, q)
    }

    fn temperatures(&self) -> Joints {
        self.manager.temperatures()
    }

    fn is_operational(&self) -> bool {
        self.manager.is_operational()
    }

    fn status(&self) -> DriveStatus {
        Drives::status(&self.manager)
    }

    fn fault_code(&self) -> Option<u8> {
        Drives::fault_code(&self.manager)
    }

    fn fault(&self) -> Option<Text> {
        Drives::fault(&self.manager)
    }

    fn has_fault(&self) -> bool {
        self.manager.fault().is_some()
    }

    fn notice(&self) -> Option<Text> {
        Drives::notice(&self.manager)
    }
}

impl<B: CanBus> DriveSide for CanDrives<B> {
    fn receive(&mut self, now: f64) -> bool {
        let running = self.bus.advance_to(now);
        self.manager.receive(&mut self.bus);
        running
    }

    fn measured(&self) -> Joints {
        self.manager.measured()
    }

    fn transmit(&mut self, now: f64, _elapsed: f64, command: Option<&Joints>) {
        self.manager.transmit(now, command, &mut self.bus);
    }
}
