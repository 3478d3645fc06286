//! The STM32F4 RNG's draw procedure (RM0090 §24, "Random number
//! generator"), over its status and data registers ([`RngRegs`]) so that it
//! is the same on the part and against a model (host-tests `rng_draw.rs`).
//!
//! What the reference manual requires, and how it is met here:
//! - A word is read only when `DRDY` is set with neither `SECS` (seed
//!   error) nor `CECS` (clock error) set, and kept only if neither is set
//!   after the read; `SEIS`/`CEIS`, which latch an error until cleared,
//!   are cleared before the draw and then refuse the words too. No word
//!   read with an error flag is ever used.
//! - A seed error: clear `SEIS`, clear then set `RNGEN` to restart, and
//!   discard every word drawn so far (RM0090 §24.3.2); at most
//!   [`SEED_RESTARTS`] restarts.
//! - A clock error (`PLL48CLK` missing or below `HCLK / 16`): the RNG
//!   produces nothing valid until its clock is fixed, so the draw fails.
//! - The first word after `RNGEN` is set is not used, only kept for the
//!   continuous test, which fails the draw when two consecutive words are
//!   equal (RM0090 §24.3.1, after FIPS PUB 140-2).
//! - Every wait on `DRDY` is bounded by a number of status reads; one that
//!   runs out fails the draw.
//!
//! A failed draw is `None` and leaves the RNG disabled: the boot goes on
//! without hardware entropy and says so (`Status.hardware_entropy`).

/// RNG_SR bits (RM0090 §24.4.2).
pub const SR_DRDY: u32 = 1 << 0;
pub const SR_CECS: u32 = 1 << 1;
pub const SR_SECS: u32 = 1 << 2;
pub const SR_CEIS: u32 = 1 << 5;
pub const SR_SEIS: u32 = 1 << 6;

/// The words a draw returns: 8 x 32 bits, the boot entropy's 32 bytes.
pub const WORDS: usize = 8;
/// Restarts after a seed error before the draw gives up. A seed error is
/// rare on a healthy part; repeated ones mean its noise source is faulty.
pub const SEED_RESTARTS: u32 = 3;

/// The RNG's registers as the draw uses them.
pub trait RngRegs {
    /// RNG_SR.
    fn status(&mut self) -> u32;
    /// RNG_DR (reading it clears `DRDY` until the next word).
    fn data(&mut self) -> u32;
    /// RNG_CR.RNGEN.
    fn set_enabled(&mut self, on: bool);
    /// Clears `SEIS` and `CEIS` (written 0; the other bits are read-only).
    fn clear_errors(&mut self);
}

/// Why an attempt stopped.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Stop {
    /// `SECS` or `SEIS`: restart and draw again.
    Seed,
    /// A clock error, a wait that ran out, or a repeated word: give up.
    Fail,
}

/// Draws [`WORDS`] words, waiting at most `budget_reads` status reads for
/// each; `None` on a clock error, a timeout, a repeated word or more than
/// [`SEED_RESTARTS`] seed errors. The RNG is left disabled either way.
pub fn draw(regs: &mut impl RngRegs, budget_reads: u32) -> Option<[u8; 4 * WORDS]> {
    let mut out = None;
    for _ in 0..=SEED_RESTARTS {
        regs.clear_errors();
        regs.set_enabled(true);
        let attempt = attempt(regs, budget_reads);
        regs.set_enabled(false);
        match attempt {
            Ok(bytes) => {
                out = Some(bytes);
                break;
            }
            Err(Stop::Seed) => continue,
            Err(Stop::Fail) => break,
        }
    }
    out
}

/// One run from `RNGEN` set: the discarded first word, then [`WORDS`]
/// words, each differing from the one before it.
fn attempt(regs: &mut impl RngRegs, budget_reads: u32) -> Result<[u8; 4 * WORDS], Stop> {
    let mut previous = word(regs, budget_reads)?;
    let mut out = [0u8; 4 * WORDS];
    for chunk in out.chunks_exact_mut(4) {
        let w = word(regs, budget_reads)?;
        if w == previous {
            return Err(Stop::Fail);
        }
        chunk.copy_from_slice(&w.to_le_bytes());
        previous = w;
    }
    Ok(out)
}

/// The next word, read only when `DRDY` is set and no error flag is, and
/// kept only if none is set after the read either.
fn word(regs: &mut impl RngRegs, budget_reads: u32) -> Result<u32, Stop> {
    for _ in 0..budget_reads {
        let sr = regs.status();
        errors(sr)?;
        if sr & SR_DRDY != 0 {
            let w = regs.data();
            errors(regs.status())?;
            return Ok(w);
        }
    }
    Err(Stop::Fail)
}

/// A status word's error flags: a clock error fails the draw, a seed
/// error restarts it.
fn errors(sr: u32) -> Result<(), Stop> {
    if sr & (SR_CECS | SR_CEIS) != 0 {
        Err(Stop::Fail)
    } else if sr & (SR_SECS | SR_SEIS) != 0 {
        Err(Stop::Seed)
    } else {
        Ok(())
    }
}
