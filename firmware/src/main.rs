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
//! On the host this crate compiles to an empty `main`, so that `cargo clippy --workspace
//! --all-targets` works without the thumb target.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(all(target_os = "none", not(feature = "sim-drives")))]
mod can;
#[cfg(target_os = "none")]
mod clocks;
#[cfg(target_os = "none")]
mod config;
#[cfg(target_os = "none")]
mod control;
#[cfg(target_os = "none")]
mod drives;
#[cfg(target_os = "none")]
mod link;
#[cfg(target_os = "none")]
mod mcu;
#[cfg(target_os = "none")]
mod net;
#[cfg(target_os = "none")]
mod settings;
#[cfg(target_os = "none")]
mod telemetry;

/// Host builds: nothing to run (the firmware only makes sense on the microcontroller).
#[cfg(not(target_os = "none"))]
fn main() {}
