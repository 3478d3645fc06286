//! The watchdog, fed by the main loop: while it waits for bytes
//! and after every byte it handles. An epoch that hangs stops the feeding;
//! the watchdog then fires and the unit records `Watchdog` and resets
//! (`fault`). Timeout 2 s, above the worst-case epoch (hundreds of ms at
//! reset clocks, BENCHMARKS.md).
//!
//! - `board-qemu`: the CMSDK APB watchdog of mps2-an386 (0x4000_8000,
//!   WDOGCLK 25 MHz, ARM DDI 0479C §4.4), interrupt on NMI. Its first
//!   expiry raises the NMI, whose handler records and resets; the second
//!   (RESEN) resets in hardware should the handler not run. The waiting
//!   loop sleeps in WFI; SysTick's exception wakes it every 2^24 ticks
//!   (0.67 s) to feed.
//! - `board-stm32f4`: the IWDG (LSI ~32 kHz, /64, reload 1000: ~2 s).

use core::ptr::write_volatile;

#[cfg(feature = "board-qemu")]
mod imp {
    use super::write_volatile;

    const BASE: usize = 0x4000_8000;
    const LOAD: usize = 0x00;
    const CTRL: usize = 0x08;
    const INTCLR: usize = 0x0C;
    const LOCK: usize = 0xC00;
    const UNLOCK_KEY: u32 = 0x1ACC_E551;
    const CTRL_INTEN: u32 = 1 << 0;
    const CTRL_RESEN: u32 = 1 << 1;
    /// 2 s at 25 MHz to the first expiry.
    const LOAD_2S: u32 = 50_000_000;

    fn reg(offset: usize, v: u32) {
        // SAFETY: a register of the CMSDK watchdog of this machine.
        unsafe { write_volatile((BASE + offset) as *mut u32, v) }
    }

    pub fn start() {
        reg(LOCK, UNLOCK_KEY);
        reg(LOAD, LOAD_2S);
        reg(CTRL, CTRL_INTEN | CTRL_RESEN);
        reg(LOCK, 0);
    }

    pub fn feed() {
        reg(LOCK, UNLOCK_KEY);
        reg(INTCLR, 1);
        reg(LOCK, 0);
    }
}

#[cfg(feature = "board-stm32f4")]
mod imp {
    use super::write_volatile;

    const IWDG_KR: usize = 0x4000_3000;
    const IWDG_PR: usize = 0x4000_3004;
    const IWDG_RLR: usize = 0x4000_3008;

    fn reg(addr: usize, v: u32) {
        // SAFETY: an IWDG register of this part.
        unsafe { write_volatile(addr as *mut u32, v) }
    }

    pub fn start() {
        reg(IWDG_KR, 0xCCCC); // start (LSI on)
        reg(IWDG_KR, 0x5555); // unlock PR/RLR
        reg(IWDG_PR, 4); // /64
        reg(IWDG_RLR, 1000); // 1000 / (32 kHz / 64) = 2 s
        reg(IWDG_KR, 0xAAAA);
    }

    pub fn feed() {
        reg(IWDG_KR, 0xAAAA);
    }
}

pub use imp::{feed, start};
