//! The drive side of the arm: the core's CANopen [`DriveManager`] on a CAN bus, the bus chosen
//! at build time in this one place.
//!
//! * default: FDCAN1 ([`crate::can::Fdcan`]) to the real drives;
//! * feature `sim-drives`: the core's `VirtualBus` with a simulated Whistle for every drive
//!   of the robot (`VirtualBus::for_robot`), advanced to the tick's time before the manager
//!   reads it. A bare board runs the whole drive path — manager, frames, flow control — with
//!   no arm and no transceiver attached.
//! * on Linux (the host build): that simulated bus, or with `ARMGATE_CAN=socketcan:IFACE` a
//!   SocketCAN interface (the adapter armgate-sim uses, crate `armgate-socketcan`), so that the
//!   firmware's own tasks drive real drives or the Whistle simulator (`armgate-sim --whistles`)
//!   through the kernel's CAN stack.
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

#[cfg(all(feature = "sim-drives", target_os = "none"))]
pub mod bus {
    use armgate_core::config::ValidRobot;
    use armgate_core::sim::VirtualBus;
    use embassy_stm32::{
        Peri,
        peripherals::{FDCAN1, PD0, PD1},
    };
    use static_cell::StaticCell;

    /// The simulated bus (≈ 24 KB: a static, never on the stack).
    pub type Bus = &'static mut VirtualBus;

    static VIRTUAL_BUS: StaticCell<VirtualBus> = StaticCell::new();

    /// Simulated Whistles at their home positions; FDCAN1 and its pins stay unused.
    pub fn open(
        robot: &ValidRobot,
        _peri: Peri<'static, FDCAN1>,
        _rx: Peri<'static, PD0>,
        _tx: Peri<'static, PD1>,
    ) -> Bus {
        simulated_at(robot, &robot.home())
    }

    /// Simulated Whistles with their encoders at joint positions `q`.
    fn simulated_at(robot: &ValidRobot, q: &[f64]) -> Bus {
        VIRTUAL_BUS.init_with(|| VirtualBus::for_robot_at(robot, q))
    }

    pub const DESCRIPTION: &str =
        "CANopen drive manager on a simulated CAN bus with simulated Whistles (sim-drives)";
}

#[cfg(not(target_os = "none"))]
pub mod bus {
    use armgate_core::config::ValidRobot;
    use armgate_core::sim::VirtualBus;
    use armgate_socketcan::{LinuxBus, Pacer, SocketCan, explain};
    use static_cell::StaticCell;

    /// The simulated bus, or a SocketCAN interface.
    pub type Bus = LinuxBus<&'static mut VirtualBus>;

    static VIRTUAL_BUS: StaticCell<VirtualBus> = StaticCell::new();

    /// Simulated Whistles with their encoders at joint positions `q` (tests start the arm
    /// where they need it).
    pub fn simulated_at(robot: &ValidRobot, q: &[f64]) -> Bus {
        LinuxBus::Simulated(VIRTUAL_BUS.init_with(|| VirtualBus::for_robot_at(robot, q)))
    }

    /// SocketCAN interface `iface`, its writes held to the robot file's bit rate if `paced`
    /// (a bus without bit timing, as armgate-sim's `--pace-can`).
    pub fn socketcan(robot: &ValidRobot, iface: &str, paced: bool) -> Result<Bus, String> {
        let pacer = paced.then(|| Pacer::new(robot.drives.can_bitrate));
        SocketCan::open(iface, pacer)
            .map(LinuxBus::SocketCan)
            .map_err(|e| explain(iface, &e))
    }

    /// What the bus is, for the start-up line.
    pub fn describe(bus: &Bus) -> &'static str {
        match bus {
            LinuxBus::Simulated(_) => {
                "CANopen drive manager on a simulated CAN bus with simulated Whistles"
            }
            LinuxBus::SocketCan(_) => "CANopen drive manager on SocketCAN",
        }
    }
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
#[cfg(target_os = "none")]
pub fn describe() -> &'static str {
    bus::DESCRIPTION
}
