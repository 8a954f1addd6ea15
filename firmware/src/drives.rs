//! The drive side of the arm: the core's CANopen [`DriveManager`] on a CAN bus, the bus chosen
//! at build time in this one place.
//!
//! * default: FDCAN1 ([`crate::can::Fdcan`]) to the real drives;
//! * feature `sim-drives`, and always on the host: the core's `VirtualBus` with a simulated Whistle for every drive
//!   of the robot (`VirtualBus::for_robot`), advanced to the tick's time before the manager
//!   reads it. A bare board runs the whole drive path — manager, frames, flow control — with
//!   no arm and no transceiver attached.
//!
//! The core's [`CanDrives`] is the cycle's drive side on either bus (the simulated one is
//! brought up to the tick's time by the cycle). The manager is started at power-up, as the
//! seed auto-started its robot component.

use armgate_core::config::ValidRobot;
use armgate_core::cycle::CanDrives;
use armgate_core::drives::DriveSettings;

#[cfg(all(target_os = "none", not(feature = "sim-drives")))]
pub mod bus {
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

    pub const DESCRIPTION: &str = "CANopen drive manager on FDCAN1 (PD0 RX, PD1 TX)";
}

#[cfg(any(feature = "sim-drives", not(target_os = "none")))]
pub mod bus {
    use armgate_core::config::ValidRobot;
    use armgate_core::sim::VirtualBus;
    #[cfg(target_os = "none")]
    use embassy_stm32::{
        Peri,
        peripherals::{FDCAN1, PD0, PD1},
    };
    use static_cell::StaticCell;

    /// The simulated bus (≈ 24 KB: a static, never on the stack).
    pub type Bus = &'static mut VirtualBus;

    static VIRTUAL_BUS: StaticCell<VirtualBus> = StaticCell::new();

    /// Simulated Whistles at their home positions; FDCAN1 and its pins stay unused.
    #[cfg(target_os = "none")]
    pub fn open(
        robot: &ValidRobot,
        _peri: Peri<'static, FDCAN1>,
        _rx: Peri<'static, PD0>,
        _tx: Peri<'static, PD1>,
    ) -> Bus {
        simulated_at(robot, &robot.home())
    }

    /// Simulated Whistles with their encoders at joint positions `q` (the host has no FDCAN;
    /// tests start the arm where they need it).
    pub fn simulated_at(robot: &ValidRobot, q: &[f64]) -> Bus {
        VIRTUAL_BUS.init_with(|| VirtualBus::for_robot_at(robot, q))
    }

    pub const DESCRIPTION: &str =
        "CANopen drive manager on a simulated CAN bus with simulated Whistles (sim-drives)";
}

/// The drive manager and its bus, as the cycle's drive side.
pub type BoardDrives = CanDrives<bus::Bus>;

/// Starts the drive manager on `bus` ([`bus::open`] on the board). Panics (before the watchdog
/// runs) if the drive manager refuses the robot, which `build.rs` already rules out for the
/// embedded robot: it runs the same check with the same default settings and fails the build
/// with the reason, so the reason's text is not linked for a message the board never prints.
// Once at boot, never on the tick: kept out of `main` and marked cold, which LTO compiles
// smaller (docs/firmware.md, "The boot's share").
#[inline(never)]
#[cold]
pub fn new(robot: &ValidRobot, bus: bus::Bus) -> BoardDrives {
    match CanDrives::started(robot, &DriveSettings::default(), bus) {
        Ok(drives) => drives,
        Err(_) => defmt::panic!(
            "drives: the drive manager refuses the embedded robot: rebuild the firmware, \
             build.rs names the reason"
        ),
    }
}

/// What [`new`] builds, for the boot log.
pub fn describe() -> &'static str {
    bus::DESCRIPTION
}
