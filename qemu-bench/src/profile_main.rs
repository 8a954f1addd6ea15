//! Instruction counts of planning jerk-limited (double-S) profiles on a Cortex-M7, in QEMU.
//!
//! The third binary of `armgate-qemu-bench` (see `main.rs` for how instructions are counted),
//! on its own so that the other two's machine code, and so their counts, do not change with
//! it: [`profile`] plans the randomised test's cases. `qemu-bench/run.sh` runs it last.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[macro_use]
mod entry;

bench_main!(profile => profile::run);
