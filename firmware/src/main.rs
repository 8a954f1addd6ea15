//! armgate firmware for the STM32H743 (NUCLEO-H743ZI2): the core on the microcontroller.
//!
//! It runs exactly the core that `armgate-sim` runs; the firmware only moves bytes and time.
//! Two embassy executors share the CPU:
//!
//! * a high-priority **interrupt executor** (on the otherwise unused `UART4` vector) runs the
//!   control tick ([`control`]): client requests, the core's tick, the drive command, the
//!   independent watchdog. It owns the core's state;
//! * the **thread executor** (lowest priority, sleeps with `WFE`) runs the network stack and
//!   the UDP server ([`net`]), and the status line ([`telemetry`]). Datagrams pass between the
//!   two through bounded queues ([`link`]).
//!
//! The drive side is the core's CANopen drive manager; its bus is chosen in one place
//! ([`drives`]): FDCAN1 ([`can`], the default) or, with feature `sim-drives`, a simulated bus
//! with simulated Whistles inside the firmware.
//! The robot description ([`config`], `ROBOT=robots/....toml`) and the network settings
//! ([`settings`], `ARMGATE_*`) are embedded at build time.
//! On Linux the same tasks run on embassy's std executor ([`host`]): embassy-net over a TAP
//! device instead of the Ethernet MAC, the simulated bus instead of FDCAN1, no watchdog
//! (tools/firmware-e2e.sh; docs/firmware.md).
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(all(target_os = "none", not(feature = "sim-drives")))]
mod can;
#[cfg(target_os = "none")]
mod clocks;
mod config;
mod control;
mod drives;
#[cfg(target_os = "none")]
mod eth;
#[cfg(not(target_os = "none"))]
mod host;
mod ingress;
mod link;
#[cfg(target_os = "none")]
mod mcu;
mod net;
mod sender;
mod settings;
mod telemetry;

/// The board's peripherals behind the seams the tasks use (network driver, watchdog).
#[cfg(not(target_os = "none"))]
use host as board;
#[cfg(target_os = "none")]
use mcu as board;

/// On the host: the same tasks on embassy's std executor, over a TAP device.
#[cfg(not(target_os = "none"))]
fn main() {
    host::main()
}
