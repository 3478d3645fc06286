//! The firmware's one static-allocation pattern: each large object (the
//! server, the particle-filter engines) is a
//! `static` [`ConstStaticCell`] initialised by a `const` value and taken
//! once, as `&'static mut`, by its owner (the link's receive ring, which
//! its interrupt shares, is a `const`-initialised static behind a
//! critical-section mutex instead: `link_rx`). The value is in the image
//! (`.data`, copied from flash by cortex-m-rt before `main`), or in `.bss`
//! when all its bytes are zero (the engines' `EMPTY` values are): it is
//! never built on the stack at run time. A second take is a programming
//! error and halts the unit.
//!
//! On the STM32F4 the particle filter's engine is in the core-coupled
//! memory (`.ccmram`, memory-stm32f4.x), which the runtime neither loads
//! nor zeroes: `zero_ccm` (in that board's build) makes it `.bss`-like at
//! the top of `main`, so that a cell there holds its all-zero `const`
//! value as it would in `.bss`.
//!
//! Two statics are deliberately left uninitialised, because their point
//! is the bytes RAM holds at boot: the reset record that survives a
//! reset (`fault.rs`) and the power-on SRAM noise (`provision.rs`).

pub use static_cell::ConstStaticCell;

use crate::board;

/// Takes `cell`'s value; halts if it was taken before.
pub fn take<T>(cell: &'static ConstStaticCell<T>) -> &'static mut T {
    match cell.try_take() {
        Some(value) => value,
        None => board::halt(),
    }
}

/// Zero-fills the `.ccmram` section (from its start to its end symbol,
/// memory-stm32f4.x), as cortex-m-rt zeroes `.bss`.
///
/// # Safety
/// Call once, first thing in `main`, before any reference to a static in
/// `.ccmram` exists; only values whose bytes are all zero may be placed
/// there (they are then their `const` initial value).
#[cfg(feature = "board-stm32f4")]
pub unsafe fn zero_ccm() {
    extern "C" {
        static mut __sccmram: u32;
        static mut __eccmram: u32;
    }
    let start = core::ptr::addr_of_mut!(__sccmram);
    let end = core::ptr::addr_of_mut!(__eccmram);
    let mut word = start;
    while word < end {
        // SAFETY: [start, end) is the `.ccmram` section, word-aligned (the
        // script aligns both symbols to 8); nothing references it yet.
        unsafe {
            word.write_volatile(0);
            word = word.add(1);
        }
    }
}
