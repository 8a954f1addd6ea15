//! Instruction counts of one full control tick of armgate's core on a Cortex-M7, in QEMU.
//!
//! The second binary of `armgate-qemu-bench` (see `main.rs` for how instructions are counted):
//! the firmware's per-tick work — `CommandHandler` and the `DriveManager` on a virtual bus of
//! simulated Whistles, in Cartesian mode — and its parts ([`tick`]), the requests that start a
//! move, and the stack they need.
//! `qemu-bench/run.sh` builds and runs it after the kinematics benchmark.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[macro_use]
mod entry;

bench_main!(stack, tick => tick::run);
