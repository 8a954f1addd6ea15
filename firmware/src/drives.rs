//! The drive side of the arm: the core's CANopen [`DriveManager`] on a CAN bus, the bus chosen
//! at build time in this one place.
//!
//! * default: FDCAN1 ([`crate::can::Fdcan`]) to the real drives;
//! * feature `sim-drives`: the core's [`VirtualBus`] with a simulated Whistle for every drive
//!   of the robot (`VirtualBus::for_robot`), advanced to the tick's time before the manager
//!   reads it. A bare board runs the whole drive path — manager, frames, flow control — with
//!   no arm and no transceiver attached.
//!
//! Per tick the control task calls [`BoardDrives::receive`], `CommandHandler::tick` with
//! [`BoardDrives::measured`] and [`BoardDrives::manager`], then [`BoardDrives::transmit`] —
//! the order of `armgate-sim`'s drive backend. The manager is started at power-up, as the
//! seed auto-started its robot component.

use armgate_core::config::ValidRobot;
use armgate_core::drives::{DriveManager, DriveSettings};
use armgate_core::kinematics::Joints;
use embassy_stm32::Peri;
use embassy_stm32::peripherals::{FDCAN1, PD0, PD1};

#[cfg(not(feature = "sim-drives"))]
mod bus {
    use armgate_core::config::ValidRobot;
    use embassy_stm32::Peri;
    use embassy_stm32::peripherals::{FDCAN1, PD0, PD1};

    pub use crate::can::Fdcan as Bus;

    /// FDCAN1 at the robot's bit rate.
    pub fn open(
        robot: &ValidRobot,
        peri: Peri<'static, FDCAN1>,
        rx: Peri<'static, PD0>,
        tx: Peri<'static, PD1>,
    ) -> Bus {
        Bus::new(peri, rx, tx, robot.drives.can_bitrate)
    }

    /// The real bus runs by itself.
    pub fn advance(_bus: &mut Bus, _now: f64) -> bool {
        true
    }

    pub const DESCRIPTION: &str = "CANopen drive manager on FDCAN1 (PD0 RX, PD1 TX)";
}

#[cfg(feature = "sim-drives")]
mod bus {
    use armgate_core::config::ValidRobot;
    use armgate_core::drives::{BusState, CanBus, TxError, VirtualBus};
    use armgate_protocol::can::CanFrame;
    use embassy_stm32::Peri;
    use embassy_stm32::peripherals::{FDCAN1, PD0, PD1};
    use static_cell::StaticCell;

    /// The simulated bus (≈ 24 KB: a static, never on the stack).
    pub struct Bus(&'static mut VirtualBus);

    impl CanBus for Bus {
        fn try_transmit(&mut self, frame: &CanFrame) -> Result<(), TxError> {
            self.0.try_transmit(frame)
        }

        fn try_receive(&mut self) -> Option<CanFrame> {
            self.0.try_receive()
        }

        fn state(&self) -> BusState {
            self.0.state()
        }
    }

    static VIRTUAL_BUS: StaticCell<VirtualBus> = StaticCell::new();

    /// Simulated Whistles at their home positions; FDCAN1 and its pins stay unused.
    pub fn open(
        robot: &ValidRobot,
        _peri: Peri<'static, FDCAN1>,
        _rx: Peri<'static, PD0>,
        _tx: Peri<'static, PD1>,
    ) -> Bus {
        Bus(VIRTUAL_BUS.init_with(|| VirtualBus::for_robot(robot)))
    }

    /// Runs the simulated bus and drives up to `now` (s); false if the simulation stalled.
    pub fn advance(bus: &mut Bus, now: f64) -> bool {
        bus.0.advance(now).is_ok()
    }

    pub const DESCRIPTION: &str =
        "CANopen drive manager on a simulated CAN bus with simulated Whistles (sim-drives)";
}

/// The drive manager and its bus.
pub struct BoardDrives {
    manager: DriveManager,
    bus: bus::Bus,
}

impl BoardDrives {
    /// The receive half of a tick at `now` (s since start-up): the manager takes what the bus
    /// received. False if the simulated bus stalled (`sim-drives` only; counted as a tick
    /// error: the manager then sees no answers and faults by its own timeouts).
    pub fn receive(&mut self, now: f64) -> bool {
        let ok = bus::advance(&mut self.bus, now);
        self.manager.receive(&mut self.bus);
        ok
    }

    /// The joints the tick starts from.
    pub fn measured(&self) -> Joints {
        self.manager.measured()
    }

    /// The drives as the command handler sees them (ON, OF, RC, TM, faults).
    pub fn manager(&self) -> &DriveManager {
        &self.manager
    }

    /// The same, for requests.
    pub fn manager_mut(&mut self) -> &mut DriveManager {
        &mut self.manager
    }

    /// The transmit half of a tick: the manager queues this cycle's frames (`None`: hold).
    pub fn transmit(&mut self, now: f64, command: Option<&Joints>) {
        self.manager.transmit(now, command, &mut self.bus);
    }
}

/// Opens the bus and starts the drive manager. Panics (before the watchdog runs) if the drive
/// manager refuses the robot, which `build.rs` already rules out for the embedded robot.
pub fn new(
    robot: &ValidRobot,
    can: Peri<'static, FDCAN1>,
    rx: Peri<'static, PD0>,
    tx: Peri<'static, PD1>,
) -> BoardDrives {
    let mut manager = match DriveManager::new(robot, &DriveSettings::default()) {
        Ok(manager) => manager,
        Err(e) => defmt::panic!("drives: {}", defmt::Display2Format(&e)),
    };
    // The seed auto-started its robot component; a fresh manager is idle, so this succeeds.
    let _ = manager.start();
    BoardDrives {
        manager,
        bus: bus::open(robot, can, rx, tx),
    }
}

/// What [`new`] builds, for the boot log.
pub fn describe() -> &'static str {
    bus::DESCRIPTION
}
