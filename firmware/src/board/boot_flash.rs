//! The boot counter's flash (issue 35; `raim_proto::boot_counter`, whose
//! log this is): the region `RAIM_BOOT` of `memory.x` /
//! `memory-stm32f4.x`, between `__raim_boot_start` and `__raim_boot_end`,
//! in two pages, each an erase unit. Advanced once per boot, before the
//! boot nonce is derived and before the watchdog starts, with interrupts
//! masked (`Board::take` leaves them so).
//!
//! - **mps2-an386** ([`CodeMemory`]): QEMU models the code memory at 0x0
//!   as RAM, so the region is written with plain stores that behave as NOR
//!   flash does (a program clears bits, an erase sets a page to all ones).
//!   QEMU keeps it for the session only: a power cycle is a new session
//!   given the region the last one saved (docs/SAFETY.md "Boot counter").
//! - **STM32F405/407** (`Stm32f4Flash`): the flash controller (RM0090
//!   §3.6), sectors 10 and 11, programmed a word at a time (PSIZE x32,
//!   2.7-3.6 V) and erased a sector at a time, every wait bounded.
//!   QEMU's netduinoplus2 maps its flash read-only and leaves the
//!   controller unimplemented: the erase does not erase, the counter
//!   fails with a typed error and that build boots without a count.

use raim_proto::boot_counter::{self, BootCounterError, CounterFlash, FlashFault};

extern "C" {
    static __raim_boot_start: u32;
    static __raim_boot_end: u32;
}

/// The region's first address and its words per page.
fn region() -> (usize, usize) {
    // Only the symbols' addresses are taken (the linker script defines
    // them; nothing is read through them).
    let (start, end) = (
        core::ptr::addr_of!(__raim_boot_start) as usize,
        core::ptr::addr_of!(__raim_boot_end) as usize,
    );
    (start, end.saturating_sub(start) / 8)
}

/// The address of word `word` of page `page`, inside the region.
fn address(start: usize, page_words: usize, page: usize, word: usize) -> Result<usize, FlashFault> {
    if page > 1 || word >= page_words {
        return Err(FlashFault);
    }
    Ok(start + 4 * (page * page_words + word))
}

/// QEMU mps2-an386's code memory (RAM in QEMU's model).
#[cfg(feature = "board-qemu")]
pub struct CodeMemory {
    start: usize,
    page_words: usize,
}

#[cfg(feature = "board-qemu")]
impl CounterFlash for CodeMemory {
    fn page_words(&self) -> usize {
        self.page_words
    }
    fn read(&mut self, page: usize, word: usize) -> Result<u32, FlashFault> {
        let a = address(self.start, self.page_words, page, word)?;
        // SAFETY: an aligned word of the RAIM_BOOT region, which no section
        // occupies and nothing else reads or writes.
        Ok(unsafe { core::ptr::read_volatile(a as *const u32) })
    }
    fn erase(&mut self, page: usize) -> Result<(), FlashFault> {
        for w in 0..self.page_words {
            let a = address(self.start, self.page_words, page, w)?;
            // SAFETY: as in `read`.
            unsafe { core::ptr::write_volatile(a as *mut u32, u32::MAX) };
        }
        Ok(())
    }
    fn program(&mut self, page: usize, word: usize, value: u32) -> Result<(), FlashFault> {
        let a = address(self.start, self.page_words, page, word)?;
        // SAFETY: as in `read`. NOR flash only clears bits.
        unsafe {
            let old = core::ptr::read_volatile(a as *const u32);
            core::ptr::write_volatile(a as *mut u32, old & value);
        }
        Ok(())
    }
}

/// Advances the counter on the QEMU board.
#[cfg(feature = "board-qemu")]
pub fn advance() -> Result<u32, BootCounterError> {
    let (start, page_words) = region();
    boot_counter::advance(&mut CodeMemory { start, page_words })
}

/// The STM32F4's flash controller, on the two sectors of the region.
#[cfg(feature = "board-stm32f4")]
pub struct Stm32f4Flash {
    start: usize,
    page_words: usize,
    regs: &'static stm32f4xx_hal::pac::flash::RegisterBlock,
}

/// The region's first sector (RM0090 Table 5: sector 10 at 0x080C0000,
/// 128 KiB, then sector 11); `memory-stm32f4.x` places RAIM_BOOT there.
#[cfg(feature = "board-stm32f4")]
const FIRST_SECTOR: u8 = 10;
#[cfg(feature = "board-stm32f4")]
const FIRST_SECTOR_ADDRESS: usize = 0x080C_0000;
#[cfg(feature = "board-stm32f4")]
const SECTOR_WORDS: usize = 128 * 1024 / 4;

/// Status reads the controller may stay busy for: a word program takes
/// well under 100 us and a 128 KiB sector erase at most 4 s (the
/// STM32F405/407 datasheet's flash characteristics, at the slowest
/// parallelism), and a status read takes at least one core cycle, at most
/// 168 MHz: these counts outlast both at the fastest clock (the program
/// four times over), and are reached only by a controller that hangs.
#[cfg(feature = "board-stm32f4")]
const PROGRAM_WAIT_READS: u32 = 168 * 100 * 4;
#[cfg(feature = "board-stm32f4")]
const ERASE_WAIT_READS: u32 = 168_000_000 * 4;

/// FLASH_KEYR's unlock sequence (RM0090 §3.5.1).
#[cfg(feature = "board-stm32f4")]
const KEY1: u32 = 0x4567_0123;
#[cfg(feature = "board-stm32f4")]
const KEY2: u32 = 0xCDEF_89AB;

#[cfg(feature = "board-stm32f4")]
impl Stm32f4Flash {
    /// Waits, bounded, for BSY to clear; then the error flags (PGSERR,
    /// PGPERR, PGAERR, WRPERR, OPERR), cleared for the next operation.
    fn finish(&self, reads: u32) -> Result<(), FlashFault> {
        self.wait_idle(reads)?;
        let sr = self.regs.sr().read();
        let failed = sr.pgserr().bit_is_set()
            || sr.pgperr().bit_is_set()
            || sr.pgaerr().bit_is_set()
            || sr.wrperr().bit_is_set()
            || sr.operr().bit_is_set();
        self.clear_flags();
        self.regs
            .cr()
            .modify(|_, w| w.pg().clear_bit().ser().clear_bit());
        self.flush_data_cache();
        if failed {
            Err(FlashFault)
        } else {
            Ok(())
        }
    }

    /// Waits, bounded, until no flash operation is under way (BSY clear).
    fn wait_idle(&self, reads: u32) -> Result<(), FlashFault> {
        let mut left = reads;
        while self.regs.sr().read().bsy().bit_is_set() {
            left = left.checked_sub(1).ok_or(FlashFault)?;
        }
        Ok(())
    }

    fn clear_flags(&self) {
        // Write-1-to-clear (RM0090 §3.9.4).
        self.regs.sr().write(|w| {
            w.eop()
                .clear_bit_by_one()
                .operr()
                .clear_bit_by_one()
                .wrperr()
                .clear_bit_by_one()
                .pgaerr()
                .clear_bit_by_one()
                .pgperr()
                .clear_bit_by_one()
                .pgserr()
                .clear_bit_by_one()
        });
    }

    /// The ART's data cache may hold the words as they were before a
    /// program or erase (RM0090 §3.5.2): reset it, so that the reads that
    /// check the write see the flash.
    fn flush_data_cache(&self) {
        let on = self.regs.acr().read().dcen().bit_is_set();
        self.regs.acr().modify(|_, w| w.dcen().clear_bit());
        self.regs.acr().modify(|_, w| w.dcrst().set_bit());
        self.regs.acr().modify(|_, w| w.dcrst().clear_bit());
        if on {
            self.regs.acr().modify(|_, w| w.dcen().set_bit());
        }
    }

    /// Waits for any operation under way to end (RM0090 §3.6.2, §3.6.3:
    /// step 1, BSY checked first), then unlocks the control register
    /// (§3.5.1); a controller that stays busy or locked fails the
    /// operation.
    fn unlock(&self) -> Result<(), FlashFault> {
        self.wait_idle(ERASE_WAIT_READS)?;
        if self.regs.cr().read().lock().bit_is_set() {
            // SAFETY: KEYR takes any 32-bit value; these are the keys.
            self.regs.keyr().write(|w| unsafe { w.key().bits(KEY1) });
            self.regs.keyr().write(|w| unsafe { w.key().bits(KEY2) });
        }
        if self.regs.cr().read().lock().bit_is_set() {
            return Err(FlashFault);
        }
        self.clear_flags();
        Ok(())
    }

    fn lock(&self) {
        self.regs.cr().modify(|_, w| w.lock().set_bit());
    }
}

#[cfg(feature = "board-stm32f4")]
impl CounterFlash for Stm32f4Flash {
    fn page_words(&self) -> usize {
        self.page_words
    }
    fn read(&mut self, page: usize, word: usize) -> Result<u32, FlashFault> {
        let a = address(self.start, self.page_words, page, word)?;
        // SAFETY: an aligned word of sectors 10-11, mapped flash on every
        // 1 MiB STM32F405/407; nothing else uses them.
        Ok(unsafe { core::ptr::read_volatile(a as *const u32) })
    }
    /// Sector erase (RM0090 §3.6.3): SER, SNB, STRT, then BSY.
    fn erase(&mut self, page: usize) -> Result<(), FlashFault> {
        let sector = match page {
            0 => FIRST_SECTOR,
            1 => FIRST_SECTOR + 1,
            _ => return Err(FlashFault),
        };
        self.unlock()?;
        self.regs.cr().modify(|_, w| {
            // SAFETY: SNB 10 or 11, sectors of the 1 MiB part.
            unsafe { w.snb().bits(sector) };
            w.psize().psize32().ser().set_bit().pg().clear_bit()
        });
        self.regs.cr().modify(|_, w| w.strt().set_bit());
        let r = self.finish(ERASE_WAIT_READS);
        self.lock();
        r
    }
    /// Word program (RM0090 §3.6.2): PG with PSIZE x32, one word written,
    /// then BSY.
    fn program(&mut self, page: usize, word: usize, value: u32) -> Result<(), FlashFault> {
        let a = address(self.start, self.page_words, page, word)?;
        self.unlock()?;
        self.regs
            .cr()
            .modify(|_, w| w.psize().psize32().ser().clear_bit().pg().set_bit());
        // SAFETY: an aligned word of sectors 10-11, with PG set: the
        // controller programs it.
        unsafe { core::ptr::write_volatile(a as *mut u32, value) };
        let r = self.finish(PROGRAM_WAIT_READS);
        self.lock();
        r
    }
}

/// Advances the counter on the STM32F4. A layout whose region is not
/// sectors 10 and 11 is refused (`Geometry`) rather than erasing
/// whatever sectors those are.
#[cfg(feature = "board-stm32f4")]
pub fn advance() -> Result<u32, BootCounterError> {
    let (start, page_words) = region();
    if start != FIRST_SECTOR_ADDRESS || page_words != SECTOR_WORDS {
        return Err(BootCounterError::Geometry {
            page_words: u32::try_from(page_words).unwrap_or(u32::MAX),
        });
    }
    // SAFETY: the flash interface's registers. `Board::take` has used
    // them (the clock's wait states) and dropped the peripheral; nothing
    // else touches them, and interrupts are masked during the boot.
    let regs = unsafe { &*stm32f4xx_hal::pac::FLASH::ptr() };
    boot_counter::advance(&mut Stm32f4Flash {
        start,
        page_words,
        regs,
    })
}
