//! Instruction counts of one full control tick of armgate's core on a Cortex-M7, in QEMU.
//!
//! The second binary of `armgate-qemu-bench` (see `main.rs` for how instructions are counted):
//! the firmware's per-tick work — `CommandHandler` and the `DriveManager` on a virtual bus of
//! simulated Whistles, in Cartesian mode — and its parts ([`tick`]), the requests that start a
//! move, and the stack they need.
//! `qemu-bench/run.sh` builds and runs it after the kinematics benchmark.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod counter;
#[cfg(target_os = "none")]
mod mcu;
#[cfg(target_os = "none")]
mod stack;
#[cfg(target_os = "none")]
mod tick;

#[cfg(target_os = "none")]
#[cortex_m_rt::entry]
fn main() -> ! {
    mcu::run(tick::run)
}

/// Host builds: nothing to run (the benchmark runs only in QEMU).
#[cfg(not(target_os = "none"))]
fn main() {}
