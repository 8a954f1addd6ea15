//! Instruction counting with SysTick under `qemu -icount shift=0`.

use core::hint::black_box;

use cortex_m::peripheral::SYST;
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m_semihosting::hprintln;

/// SysTick is a 24-bit down-counter; it runs with the largest reload, so that one window
/// (at most 2^24 ticks, 671 million instructions) never wraps twice.
const RELOAD: u32 = 0x00FF_FFFF;

/// Instructions in one calibration block.
const BLOCK: u32 = 10_000;
/// Calibration blocks per window.
const BLOCKS: u32 = 10;

/// A SysTick counting at the processor clock, with its calibration.
pub struct Counter {
    /// Instructions per SysTick tick, measured.
    pub instructions_per_tick: f64,
    /// Ticks of an empty measurement window (the two counter reads), mean of many.
    pub empty_ticks: f64,
    /// Ticks measured for `BLOCKS` × `BLOCK` `nop`s.
    pub calibration_ticks: u32,
}

impl Counter {
    /// Starts SysTick on the processor clock and calibrates it.
    pub fn start(mut syst: SYST) -> Self {
        syst.disable_interrupt();
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(RELOAD);
        syst.clear_current();
        syst.enable_counter();

        const EMPTY_RUNS: u32 = 1000;
        let mut empty = 0u64;
        for _ in 0..EMPTY_RUNS {
            empty += u64::from(measure(|| ()).0);
        }
        let (calibration_ticks, ()) = measure(|| {
            for _ in 0..black_box(BLOCKS) {
                nop_block();
            }
        });
        let empty_ticks = empty as f64 / f64::from(EMPTY_RUNS);
        let block_ticks = (f64::from(calibration_ticks) - empty_ticks).max(1.0);
        Self {
            instructions_per_tick: f64::from(BLOCK * BLOCKS) / block_ticks,
            empty_ticks,
            calibration_ticks,
        }
    }

    /// Instructions executed by a call that measured `ticks` on average.
    pub fn instructions(&self, ticks: f64) -> f64 {
        (ticks - self.empty_ticks) * self.instructions_per_tick
    }

    /// Instructions in the calibration window, by construction.
    pub const fn calibration_instructions() -> u32 {
        BLOCK * BLOCKS
    }

    /// Prints the calibration over semihosting: the first line of every benchmark's output.
    pub fn print_calibration(&self) {
        hprintln!(
            "calibration: {} nop = {} SysTick ticks (empty window {:.2} ticks) -> {:.3} instructions/tick (40 expected: 1 ns per instruction, 25 MHz SysTick)",
            Self::calibration_instructions(),
            self.calibration_ticks,
            self.empty_ticks,
            self.instructions_per_tick
        );
    }
}

/// Runs `f` between two SysTick reads; returns the elapsed ticks and `f`'s result.
#[inline(always)]
pub fn measure<R>(f: impl FnOnce() -> R) -> (u32, R) {
    let start = SYST::get_current();
    // `black_box` (an opaque memory access) keeps the work between the two volatile reads.
    let f = black_box(f);
    let result = f();
    // By reference: `black_box(result)` moved the result into its argument inside the window,
    // a copy the caller does not make (650 bytes byte by byte for `solve_all`'s list, about
    // 2,400 instructions).
    black_box(&result);
    let end = SYST::get_current();
    (start.wrapping_sub(end) & RELOAD, result)
}

/// Exactly `BLOCK` `nop` instructions.
// Inline assembly is the only way to execute a known number of instructions; `unsafe` is
// required for it, and a block of `nop`s has no effect to be unsafe about.
#[allow(unsafe_code)]
#[inline(never)]
fn nop_block() {
    // SAFETY: `nop` touches no register, memory or flag.
    unsafe {
        core::arch::asm!(
            ".rept 10000",
            "nop",
            ".endr",
            options(nomem, nostack, preserves_flags)
        );
    }
}

/// Ticks of one operation over all samples.
#[derive(Default)]
pub struct Timing {
    /// Calls measured.
    pub calls: u32,
    ticks: u64,
    max_ticks: u32,
}

impl Timing {
    /// Adds one call that took `ticks`.
    pub fn add(&mut self, ticks: u32) {
        self.calls += 1;
        self.ticks += u64::from(ticks);
        self.max_ticks = self.max_ticks.max(ticks);
    }

    /// Mean and maximum instructions per call.
    pub fn instructions(&self, counter: &Counter) -> (f64, f64) {
        let mean = self.ticks as f64 / f64::from(self.calls.max(1));
        (
            counter.instructions(mean),
            counter.instructions(f64::from(self.max_ticks)),
        )
    }
}
