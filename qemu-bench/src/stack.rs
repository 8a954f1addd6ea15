//! Stack high-water mark: paint the free stack below a base with a pattern, run the code, and
//! find the lowest word that no longer holds the pattern.
//!
//! Reading and writing the memory below the stack pointer needs raw pointers; nothing else uses
//! that memory here (no interrupts are enabled in the benchmark), and the painted range is
//! checked to lie above the static data.

use core::ptr;

/// The paint.
const PATTERN: u32 = 0xA5C3_5A3C;
/// Left unpainted just below the painting function's own stack pointer (bytes).
const MARGIN: usize = 64;

/// A painted range `[bottom, top)` below `base`.
pub struct Painted {
    base: usize,
    bottom: usize,
    top: usize,
}

/// The current stack pointer.
#[inline(always)]
pub fn pointer() -> usize {
    cortex_m::register::msp::read() as usize
}

// The end of the static data, from cortex-m-rt's linker script (the heap would start there).
#[allow(unsafe_code)]
unsafe extern "C" {
    static __sheap: u32;
}

/// Paints up to `depth` bytes below `base` (a stack pointer the caller read), stopping a little
/// below this function's own frame and above the static data.
// `unsafe` is required to write memory below the stack pointer, which no Rust object owns.
#[allow(unsafe_code)]
#[inline(never)]
pub fn paint(base: usize, depth: usize) -> Painted {
    let statics_end = ptr::addr_of!(__sheap) as usize;
    let top = (pointer() - MARGIN) & !3;
    let bottom = (base.saturating_sub(depth) & !3).max((statics_end + 3) & !3);
    let mut addr = bottom;
    while addr < top {
        // SAFETY: `[bottom, top)` is RAM between the static data and this function's stack
        // frame (minus a margin): free stack, owned by no object, aligned to 4.
        unsafe { ptr::write_volatile(addr as *mut u32, PATTERN) };
        addr += 4;
    }
    Painted { base, bottom, top }
}

/// Bytes of stack used below the base since [`paint`]: from the base down to the lowest word
/// that lost the pattern (the whole painted depth if even the bottom word was written).
#[allow(unsafe_code)]
pub fn high_water(painted: &Painted) -> usize {
    let mut addr = painted.bottom;
    while addr < painted.top {
        // SAFETY: reads of the range `paint` wrote, aligned to 4.
        if unsafe { ptr::read_volatile(addr as *const u32) } != PATTERN {
            break;
        }
        addr += 4;
    }
    painted.base - addr
}
