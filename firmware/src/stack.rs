//! Stack painting: fill the unused stack with a pattern once, then find the
//! deepest word that was overwritten. Gives the worst-case stack use of
//! everything run since (BENCHMARKS.md).

use core::ptr::{read_volatile, write_volatile};

const PAINT: u32 = 0xC5AC_CE55;
/// How far below the stack pointer at painting time is painted; deeper use
/// saturates the measurement at this span.
const SPAN_BYTES: usize = 128 * 1024;
/// Left alone below the current stack pointer (painting's own frame).
const MARGIN_BYTES: usize = 256;

extern "C" {
    /// End of statically allocated RAM (cortex-m-rt).
    static __sheap: u32;
    /// Initial stack pointer (cortex-m-rt).
    static _stack_start: u32;
}

fn bounds() -> (usize, usize) {
    // Above the MPU guard region (`guard`), which faults on any access.
    let bottom = crate::guard::end().max(core::ptr::addr_of!(__sheap) as usize);
    let top = core::ptr::addr_of!(_stack_start) as usize;
    (bottom.max(top.saturating_sub(SPAN_BYTES)), top)
}

/// Paint from the bottom of the measured span up to just below the current
/// stack pointer.
pub fn paint() {
    let (bottom, _) = bounds();
    let sp = cortex_m::register::msp::read() as usize;
    let end = sp.saturating_sub(MARGIN_BYTES) & !3;
    let mut p = (bottom + 3) & !3;
    while p < end {
        // SAFETY: [bottom, sp - margin) is RAM below the live stack, unused.
        unsafe { write_volatile(p as *mut u32, PAINT) };
        p += 4;
    }
}

/// Deepest stack use since `paint`, bytes from the top of the stack.
pub fn high_water_bytes() -> u32 {
    let (bottom, top) = bounds();
    let mut p = (bottom + 3) & !3;
    // SAFETY: reads RAM inside the stack span, word-aligned.
    while p < top && unsafe { read_volatile(p as *const u32) } == PAINT {
        p += 4;
    }
    (top - p) as u32
}
