//! Instruction counts of armgate's kinematics on a Cortex-M7, measured in QEMU.
//!
//! Runs bare-metal on QEMU's `mps2-an500` machine (Cortex-M7 with a double-precision FPU) under
//! `-icount shift=0`, where virtual time advances by exactly 1 ns per executed instruction.
//! SysTick, clocked from the 25 MHz system clock, then counts one tick per 40 instructions; a
//! calibration against blocks of `nop`s checks that factor before anything is measured.
//! Prints, over semihosting, instructions per call of forward kinematics and of tracking IK for
//! every robot of `robots/`, and exits QEMU. `qemu-bench/run.sh` builds and runs it, and then the
//! second binary of this package, `armgate-qemu-tick` (`src/tick_main.rs`: one full control
//! tick). They are separate binaries so that neither changes how the compiler inlines the core
//! into the other: the counts depend on the machine code, not only on the source.
//!
//! Instructions are not cycles: a real Cortex-M7 dual-issues simple instructions, but an f64
//! divide or square root takes many cycles. The count is a deterministic, host-independent
//! measure of the work, for comparing versions of the core.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[macro_use]
mod entry;

bench_main!(bench => bench::run);
