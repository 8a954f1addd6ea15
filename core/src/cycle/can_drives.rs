//! The CANopen drive manager on its bus, as one [`DriveSide`].

use armgate_protocol::client::{DriveStatus, Severity, Text};

use super::DriveSide;
use crate::command::Drives;
use crate::config::ValidRobot;
use crate::drives::{
    CanBus, DriveFault, DriveManager, DriveSettings, DriveState, LifecycleError, SetupError,
};
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

/// `start` and `stop` only begin the transition: a start that later fails shows as a fault
/// (its `ER3x` text), and motion stays refused until [`Drives::is_operational`]. `ON` also asks
/// the bus to leave bus-off: the policy of docs/architecture.md.
impl<B: CanBus> Drives for CanDrives<B> {
    fn start(&mut self) -> Result<(), LifecycleError> {
        self.manager.start()?;
        self.bus.recover();
        Ok(())
    }

    fn stop(&mut self) -> Result<(), LifecycleError> {
        self.manager.stop()
    }

    fn recalibrate(&mut self, q: &[f64]) -> Result<(), Refusal> {
        self.manager.recalibrate(q)
    }

    fn temperatures(&self) -> Joints {
        self.manager.temperatures()
    }

    fn is_operational(&self) -> bool {
        self.manager.is_operational()
    }

    fn status(&self) -> DriveStatus {
        match self.manager.state() {
            DriveState::Idle | DriveState::Stopped => DriveStatus::Off,
            DriveState::Starting => DriveStatus::Starting,
            DriveState::Operational => DriveStatus::Running,
            DriveState::Stopping => DriveStatus::Stopping,
            DriveState::Faulted => DriveStatus::Faulted,
        }
    }

    fn fault_code(&self) -> Option<u8> {
        self.manager.fault().map(|fault| fault.code())
    }

    fn fault(&self) -> Option<Text> {
        self.manager.fault().map(|fault| fault.text())
    }

    fn has_fault(&self) -> bool {
        self.manager.fault().is_some()
    }

    /// `WN39` with the refusal's text: the PDO mapping was refused and the interpreter
    /// schedule runs instead.
    fn notice(&self) -> Option<Text> {
        self.manager
            .fallback()
            .map(|refusal| refusal.text_as(Severity::Warning))
    }
}

/// A drive fault as the client reads it: here, above the drives, which know nothing of the
/// client's protocol.
impl DriveFault {
    /// The text for the client, e.g. `ER30 J3 drive not answering`.
    pub fn text(&self) -> Text {
        self.text_as(Severity::Error)
    }

    /// The same text as an error (`ER`) or, for what is reported but does not stop the arm (a
    /// refused PDO mapping with the fallback), a warning (`WN`).
    pub fn text_as(&self, severity: Severity) -> Text {
        Text::new(severity, self.code(), self)
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
