//! Instruction counts of planning jerk-limited (double-S) profiles on a Cortex-M7, in QEMU.
//!
//! The third binary of `armgate-qemu-bench` (see `main.rs` for how instructions are counted),
//! on its own so that the other two's machine code, and so their counts, do not change with
//! it: [`profile`] plans the randomised test's cases. `qemu-bench/run.sh` runs it last.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod counter;
#[cfg(target_os = "none")]
mod mcu;
#[cfg(target_os = "none")]
mod profile;

#[cfg(target_os = "none")]
#[cortex_m_rt::entry]
fn main() -> ! {
    mcu::run(profile::run)
}

/// Host builds: nothing to run (the benchmark runs only in QEMU).
#[cfg(not(target_os = "none"))]
fn main() {}
