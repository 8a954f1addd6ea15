//! armgate firmware for the STM32H743 (NUCLEO-H743ZI2): the core on the microcontroller.
//!
//! Two embassy executors share the CPU:
//!
//! * a high-priority **interrupt executor** (on the otherwise unused `UART4` vector) runs the
//!   control tick ([`control`]), so that it preempts everything else;
//! * the **thread executor** (lowest priority, sleeps with `WFE`) will run networking (UDP),
//!   the CAN drive bus and the watchdog, which a later issue adds as tasks of their own modules.
//!
//! The robot description is embedded at build time ([`config`], `ROBOT=robots/....toml`).
//! On the host this crate compiles to an empty `main`, so that `cargo clippy --workspace
//! --all-targets` works without the thumb target.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod clocks;
#[cfg(target_os = "none")]
mod config;
#[cfg(target_os = "none")]
mod control;
#[cfg(target_os = "none")]
mod mcu;

/// Host builds: nothing to run (the firmware only makes sense on the microcontroller).
#[cfg(not(target_os = "none"))]
fn main() {}
