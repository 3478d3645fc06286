//! The monotonic boot counter (issue 35, "Nonces and keys"): a value kept
//! in flash that every boot raises before it is used, and that goes into
//! the boot nonce (`auth::boot_nonce`), so that a frame recorded in an
//! earlier power-on never verifies again, even on a board without
//! hardware entropy (docs/SAFETY.md "Boot counter").
//!
//! Sans-IO: the logic runs on any [`CounterFlash`] (the STM32F4's flash
//! controller, QEMU's code memory, a model in the tests).
//!
//! **Layout.** Two pages (erase units: on the STM32F4 two flash sectors),
//! each an append-only log of entries of two words, `[v, !v]`, with
//! `1 <= v < u32::MAX`. Erased flash reads all ones, a program clears
//! bits. The value is the largest `v` of any entry that reads back whole
//! (the pair checks), 0 when none does.
//!
//! **A boot** ([`advance`]) reads the value `n` and writes `n + 1`: in the
//! page holding the largest entry (the active page), in the entry after
//! the highest one that is not all ones; when the active page is full,
//! its largest entry is programmed again with the same bits (a torn entry
//! that happened to read whole is completed, or the boot fails), the
//! other page is erased (always: a cut may have left cells that read all
//! ones only this time) and checked to read all ones, and `n + 1` becomes
//! its first entry. With no whole entry anywhere, page 0 is erased and
//! starts the log. One entry per boot (wear levelling): a page is erased
//! once per `2 x entries` boots. Each word of the entry is then read back
//! [`READS`] times and the region read again: the boot has its value only
//! if every one of those reads gives `n + 1`; a write that does not read
//! back, or reads back right and then wrong, is a failed write, tried
//! again above it ([`ATTEMPTS`]).
//!
//! **Why it never goes back.** A write cut by a power loss leaves bits
//! partly cleared, and such cells may read differently from read to read.
//! A torn or partly erased pair reads either as the value that was being
//! written or as no valid entry (`w | m == !(!w | m')` only for
//! `m = m' = 0`, with the cut's stray bits `m`, `m'`), so a tear never
//! fabricates a value. A boot that completed wrote its value in full and
//! read it back; the page that holds it is erased only once the other
//! page holds entries above it. Every later boot therefore reads at
//! least that value and writes one more: the value used at a completed
//! boot is strictly greater than at every earlier completed boot. The
//! property test `a_boot_value_never_repeats_across_cuts_and_faults`
//! checks it over random sequences of boots, power cuts at every step
//! and flash faults.
//!
//! **What it relies on.** A program the flash reports complete need not
//! have stored what was asked: one that wrote nothing (QEMU's
//! netduinoplus2), one that stored other bits, and one whose cell reads
//! back right and then, on a later read, with a bit flipped, are each
//! caught by the read-back (the last by reading [`READS`] times) and
//! treated as a failed write: the entry is left unreadable and the value
//! is written again above it; a single wrong bit never makes a pair read
//! whole (`[v, !v]` has each bit cleared in exactly one word). What it
//! relies on is that a cell that read back the same value at every one of
//! a boot's reads keeps it (the flash's data retention): a cell that
//! decays after its boot completed could let a later boot read the value
//! below it and use the decayed value again. The property test
//! `a_boot_value_never_repeats_across_cuts_and_faults` models the writes
//! that store other bits and the cells that flip within the read-back,
//! and checks that each value a boot returns is stored in cells that
//! read it steadily.
//!
//! **Fail safe.** Any read, erase or program the flash reports failed,
//! a page that does not read erased after its erase, a region that does
//! not read back the value written at every read (after [`ATTEMPTS`]
//! writes), and a counter at the top of its range
//! are a typed [`BootCounterError`]; the unit then boots with no boot
//! count, and a keyed unit refuses every authenticated change
//! (`WireError::BootCounter`), since its nonce may have been used before.

use serde::{Deserialize, Serialize};

/// What erased flash reads.
pub const ERASED: u32 = u32::MAX;

/// A failed flash operation, as the board's flash reports it (the
/// controller's error flags, a timeout, a read outside the region).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FlashFault;

/// The counter's flash: two pages of [`Self::page_words`] words each,
/// erased a page at a time, programmed a word at a time (a program can
/// only clear bits, as NOR flash does).
pub trait CounterFlash {
    /// Words in each of the two pages.
    fn page_words(&self) -> usize;
    /// Word `word` of page `page` (0 or 1).
    fn read(&mut self, page: usize, word: usize) -> Result<u32, FlashFault>;
    /// Erases page `page`: every word reads [`ERASED`] after it.
    fn erase(&mut self, page: usize) -> Result<(), FlashFault>;
    /// Programs word `word` of page `page` with `value`.
    fn program(&mut self, page: usize, word: usize, value: u32) -> Result<(), FlashFault>;
}

/// Why this boot has no boot count.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BootCounterError {
    /// A word of the region could not be read.
    Unreadable {
        /// The page.
        page: u8,
        /// The word within it.
        word: u32,
    },
    /// The flash reported a failed erase of the page.
    EraseFailed {
        /// The page.
        page: u8,
    },
    /// The page did not read erased after its erase: the first word that
    /// did not, and what it read.
    EraseVerify {
        /// The page.
        page: u8,
        /// The word within it.
        word: u32,
        /// What it read.
        value: u32,
    },
    /// The flash reported a failed program of the word.
    ProgramFailed {
        /// The page.
        page: u8,
        /// The word within it.
        word: u32,
    },
    /// The region did not read back the value written (QEMU's
    /// netduinoplus2, whose flash ignores writes, reads the old one).
    Verify {
        /// The value written.
        expected: u32,
        /// The value the region read afterwards.
        read: u32,
    },
    /// The counter is at the top of its range (`u32::MAX - 1` boots).
    Exhausted,
    /// Pages too small to hold one entry.
    Geometry {
        /// The page's words.
        page_words: u32,
    },
}

/// The boot counter as `Status` reports it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BootCounterStatus {
    /// The platform keeps no boot counter (the host's server).
    #[default]
    Absent,
    /// This boot's value, written and read back before it was used.
    Count(u32),
    /// The counter could not be advanced: this boot has no boot count,
    /// and a keyed unit refuses every authenticated change.
    Failed(BootCounterError),
}

/// What a scan of the region found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Scan {
    /// The largest whole entry, 0 if none.
    value: u32,
    /// The page holding it.
    active: Option<usize>,
    /// Per page, the highest entry that is not all ones.
    top: [Option<usize>; 2],
    /// The page and entry of the largest whole entry.
    top_of_value: (usize, usize),
}

/// The value of an entry that reads back whole.
fn decode(a: u32, b: u32) -> Option<u32> {
    (a == !b && a != 0 && a != ERASED).then_some(a)
}

fn page_id(page: usize) -> u8 {
    u8::from(page != 0)
}

fn word_id(word: usize) -> u32 {
    u32::try_from(word).unwrap_or(u32::MAX)
}

fn read<F: CounterFlash>(f: &mut F, page: usize, word: usize) -> Result<u32, BootCounterError> {
    f.read(page, word)
        .map_err(|FlashFault| BootCounterError::Unreadable {
            page: page_id(page),
            word: word_id(word),
        })
}

fn scan<F: CounterFlash>(f: &mut F, entries: usize) -> Result<Scan, BootCounterError> {
    let mut s = Scan {
        value: 0,
        active: None,
        top: [None; 2],
        top_of_value: (0, 0),
    };
    for (page, top) in s.top.iter_mut().enumerate() {
        for e in 0..entries {
            let a = read(f, page, 2 * e)?;
            let b = read(f, page, 2 * e + 1)?;
            if a != ERASED || b != ERASED {
                *top = Some(e);
            }
            if let Some(v) = decode(a, b) {
                if v > s.value {
                    s.value = v;
                    s.active = Some(page);
                    s.top_of_value = (page, e);
                }
            }
        }
    }
    Ok(s)
}

/// The value in the region, without writing (0 when none; a tool's or a
/// test's read).
pub fn value<F: CounterFlash>(f: &mut F) -> Result<u32, BootCounterError> {
    let entries = entries(f)?;
    Ok(scan(f, entries)?.value)
}

fn entries<F: CounterFlash>(f: &F) -> Result<usize, BootCounterError> {
    match f.page_words() / 2 {
        0 => Err(BootCounterError::Geometry {
            page_words: word_id(f.page_words()),
        }),
        n => Ok(n),
    }
}

/// Attempts of one boot whose write did not read back (`Verify`): a
/// write over a cell a cut left marginal (it read erased, and kept some
/// of its stray bits) leaves that entry unreadable but no longer erased,
/// so the next attempt writes above it.
pub const ATTEMPTS: usize = 3;

/// One boot: raises the counter by one and returns the new value, once it
/// is written and the region reads it back; any failure is typed and
/// leaves the boot without a value (the module's documentation). A write
/// that does not read back is tried again above it, [`ATTEMPTS`] times in
/// all; each attempt is a whole boot's step (read, write, read back).
pub fn advance<F: CounterFlash>(f: &mut F) -> Result<u32, BootCounterError> {
    let mut last = Err(BootCounterError::Exhausted);
    for _ in 0..ATTEMPTS {
        last = attempt(f);
        if !matches!(last, Err(BootCounterError::Verify { .. })) {
            break;
        }
    }
    last
}

/// Reads of each word of a written entry: all must give the value
/// written. A cell that reads back right once and then wrong (a marginal
/// program the flash reported complete) is caught by the second or third
/// read, and the write is treated as failed.
pub const READS: usize = 3;

/// Programs entry `entry` of page `page` with `value`, then reads both
/// words back, each [`READS`] times.
fn write_entry<F: CounterFlash>(
    f: &mut F,
    page: usize,
    entry: usize,
    value: u32,
) -> Result<(), BootCounterError> {
    let words = [(2 * entry, value), (2 * entry + 1, !value)];
    for (w, v) in words {
        f.program(page, w, v)
            .map_err(|FlashFault| BootCounterError::ProgramFailed {
                page: page_id(page),
                word: word_id(w),
            })?;
    }
    for _ in 0..READS {
        for (w, v) in words {
            let back = read(f, page, w)?;
            if back != v {
                return Err(BootCounterError::Verify {
                    expected: value,
                    read: back,
                });
            }
        }
    }
    Ok(())
}

fn attempt<F: CounterFlash>(f: &mut F) -> Result<u32, BootCounterError> {
    let entries = entries(f)?;
    let s = scan(f, entries)?;
    let target = s
        .value
        .checked_add(1)
        .filter(|&t| t != ERASED)
        .ok_or(BootCounterError::Exhausted)?;
    // Where the new entry goes, and whether its page is erased first.
    let (page, entry, erase) = match s.active {
        Some(p) => match s.top.get(p).copied().flatten() {
            Some(t) if t + 1 < entries => (p, t + 1, false),
            // Erased even when it reads erased: a cut write may have left
            // marginal cells that read all ones this time.
            _ => (1 - p, 0, true),
        },
        // No whole entry anywhere (a new region, or a first write cut):
        // nothing of value to keep.
        None => (0, 0, true),
    };
    if page != s.active.unwrap_or(page) {
        // The page switch erases the page of the earlier entries: the
        // largest entry, which may be a torn write that happened to read
        // whole, is programmed again first (the same bits: a whole entry
        // is unchanged, a torn one completed) and must read back, so that
        // the erase never leaves only a marginal entry above the value
        // last used.
        let (p, e) = s.top_of_value;
        write_entry(f, p, e, s.value)?;
    }
    if erase {
        f.erase(page)
            .map_err(|FlashFault| BootCounterError::EraseFailed {
                page: page_id(page),
            })?;
        for w in 0..2 * entries {
            let v = read(f, page, w)?;
            if v != ERASED {
                return Err(BootCounterError::EraseVerify {
                    page: page_id(page),
                    word: word_id(w),
                    value: v,
                });
            }
        }
    }
    // The entry must read back, and then the region must read it as the
    // largest: a torn entry elsewhere that happens to read whole with the
    // same value must not stand in for it.
    write_entry(f, page, entry, target)?;
    let after = scan(f, entries)?;
    if after.value != target {
        return Err(BootCounterError::Verify {
            expected: target,
            read: after.value,
        });
    }
    Ok(target)
}

#[cfg(test)]
mod tests {
    use super::*;
    extern crate std;
    use std::vec;
    use std::vec::Vec;

    /// One flash cell of the model.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    enum Cell {
        /// Reads `v`, every time.
        Good(u32),
        /// A program of `intended` over `old` cut by a power loss: some of
        /// the bits it was clearing are cleared, and a marginal cell reads
        /// differently from read to read (`old & (intended | m)`, a fresh
        /// random `m` at every read).
        TornProgram { old: u32, intended: u32 },
        /// An erase of `old` cut by a power loss: `old | m`, a fresh random
        /// `m` at every read.
        TornErase { old: u32 },
        /// A program the flash reported complete over a marginal cell: it
        /// reads `value` at its next `good_reads` reads, then with bit
        /// `bit` flipped at every later read.
        Weak {
            value: u32,
            good_reads: usize,
            bit: u32,
        },
    }

    /// What the model's flash does at its next operation.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    enum Fault {
        /// Works.
        None,
        /// The power is cut during it: the operation is torn, and every
        /// later one of this boot fails (the boot never completes).
        Cut,
        /// Reports failure, having torn the cells it was changing.
        Fail,
        /// Reports success and changes nothing (QEMU's netduinoplus2).
        Ignore,
        /// A read that fails.
        Unreadable,
        /// A program that reports success and stores other bits: some it
        /// should clear left set, some it should keep cleared (stable).
        /// Only a program that clears a bit (one that changes nothing
        /// pulses no cell).
        Corrupt,
        /// A program that reports success and stores the value in a
        /// marginal cell that reads it right `n` times, then with a bit
        /// flipped ([`Cell::Weak`]). Only a program that clears a bit.
        Weak(usize),
    }

    /// NOR flash with power cuts, failures and marginal cells.
    struct Model {
        pages: [Vec<Cell>; 2],
        rng: u64,
        /// The operation (counted from the boot's first) that faults, and how.
        fault_at: Option<(usize, Fault)>,
        ops: usize,
        cut: bool,
        /// Every erase and program reports success and changes nothing
        /// (QEMU's netduinoplus2).
        read_only: bool,
    }

    impl Model {
        fn new(page_words: usize, seed: u64) -> Self {
            Model {
                pages: [
                    vec![Cell::Good(ERASED); page_words],
                    vec![Cell::Good(ERASED); page_words],
                ],
                rng: seed | 1,
                fault_at: None,
                ops: 0,
                cut: false,
                read_only: false,
            }
        }
        fn random(&mut self) -> u32 {
            // xorshift64*
            self.rng ^= self.rng >> 12;
            self.rng ^= self.rng << 25;
            self.rng ^= self.rng >> 27;
            (self.rng.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 32) as u32
        }
        /// Random bits, biased so that whole words often come out all
        /// ones or all zeros (a marginal cell read as erased or as written).
        fn stray(&mut self) -> u32 {
            match self.random() % 4 {
                0 => 0,
                1 => u32::MAX,
                _ => self.random(),
            }
        }
        fn cell_value(&mut self, c: Cell) -> u32 {
            match c {
                Cell::Good(v) => v,
                Cell::TornProgram { old, intended } => old & (intended | self.stray()),
                Cell::TornErase { old } => old | self.stray(),
                Cell::Weak {
                    value,
                    good_reads,
                    bit,
                } => {
                    if good_reads > 0 {
                        value
                    } else {
                        value ^ (1 << bit)
                    }
                }
            }
        }
        /// Reads the cell at `(page, word)`: a weak cell uses up one of
        /// its good reads.
        fn read_cell(&mut self, page: usize, word: usize) -> Option<u32> {
            let c = *self.pages[page].get(word)?;
            if let Cell::Weak {
                value,
                good_reads,
                bit,
            } = c
            {
                self.pages[page][word] = Cell::Weak {
                    value,
                    good_reads: good_reads.saturating_sub(1),
                    bit,
                };
            }
            Some(self.cell_value(c))
        }
        /// Whether a whole entry `[v, !v]` is stored in cells that read it
        /// at every read (written durably).
        fn holds_durably(&self, v: u32) -> bool {
            self.pages.iter().any(|p| {
                p.chunks_exact(2)
                    .any(|e| e[0] == Cell::Good(v) && e[1] == Cell::Good(!v))
            })
        }
        fn boot(&mut self, fault_at: Option<(usize, Fault)>) {
            self.fault_at = fault_at;
            self.ops = 0;
            self.cut = false;
        }
        fn next_fault(&mut self) -> Fault {
            if self.cut {
                return Fault::Cut;
            }
            let f = match self.fault_at {
                Some((at, f)) if at == self.ops => f,
                _ => Fault::None,
            };
            self.ops += 1;
            f
        }
    }

    /// The bits of a cell that read 0 at every read.
    fn stable_zeros(c: Cell) -> u32 {
        match c {
            Cell::Good(v) => !v,
            Cell::TornProgram { old, .. } => !old,
            Cell::TornErase { .. } => 0,
            Cell::Weak { value, bit, .. } => !value & !(1 << bit),
        }
    }

    impl CounterFlash for Model {
        fn page_words(&self) -> usize {
            self.pages[0].len()
        }
        fn read(&mut self, page: usize, word: usize) -> Result<u32, FlashFault> {
            match self.next_fault() {
                Fault::Cut if self.cut => Err(FlashFault),
                Fault::Cut => {
                    self.cut = true;
                    Err(FlashFault)
                }
                Fault::Unreadable => Err(FlashFault),
                _ => self.read_cell(page, word).ok_or(FlashFault),
            }
        }
        fn erase(&mut self, page: usize) -> Result<(), FlashFault> {
            if self.read_only {
                return Ok(());
            }
            match self.next_fault() {
                Fault::Cut if self.cut => Err(FlashFault),
                f @ (Fault::Cut | Fault::Fail) => {
                    self.cut |= f == Fault::Cut;
                    for k in 0..self.pages[page].len() {
                        let old = self.cell_value(self.pages[page][k]);
                        self.pages[page][k] = if old == ERASED {
                            Cell::Good(ERASED)
                        } else {
                            Cell::TornErase { old }
                        };
                    }
                    Err(FlashFault)
                }
                Fault::Ignore => Ok(()),
                Fault::None | Fault::Unreadable | Fault::Corrupt | Fault::Weak(_) => {
                    self.pages[page].fill(Cell::Good(ERASED));
                    Ok(())
                }
            }
        }
        fn program(&mut self, page: usize, word: usize, value: u32) -> Result<(), FlashFault> {
            if self.read_only {
                return Ok(());
            }
            let mut f = self.next_fault();
            let c = *self.pages[page].get(word).ok_or(FlashFault)?;
            // A program pulses only the bits it clears: a word programmed
            // with the bits it already holds (the page switch's second
            // program of a whole entry) is left as it is, so a program
            // that stores other bits or leaves a marginal cell needs a bit
            // to clear.
            if matches!(f, Fault::Corrupt | Fault::Weak(_)) && !value & !stable_zeros(c) == 0 {
                f = Fault::None;
            }
            match f {
                Fault::Cut if self.cut => Err(FlashFault),
                Fault::Cut | Fault::Fail => {
                    self.cut |= f == Fault::Cut;
                    let old = self.cell_value(c);
                    self.pages[page][word] = Cell::TornProgram {
                        old,
                        intended: value,
                    };
                    Err(FlashFault)
                }
                Fault::Ignore => Ok(()),
                Fault::Corrupt => {
                    // Some bits to clear left set, some to keep cleared;
                    // at least one bit wrong.
                    let old = self.cell_value(c);
                    let mut stored = old & ((value | self.random()) & !self.random());
                    if stored == old & value {
                        stored ^= 1 << (self.random() % 32);
                    }
                    self.pages[page][word] = Cell::Good(stored);
                    Ok(())
                }
                Fault::Weak(good_reads) => {
                    let old = self.cell_value(c);
                    let bit = self.random() % 32;
                    self.pages[page][word] = Cell::Weak {
                        value: old & value,
                        good_reads,
                        bit,
                    };
                    Ok(())
                }
                Fault::None | Fault::Unreadable => {
                    // A completed program over a marginal cell: the bits it
                    // clears, and whichever the tear had cleared.
                    let old = self.cell_value(c);
                    self.pages[page][word] = Cell::Good(old & value);
                    Ok(())
                }
            }
        }
    }

    /// Verifies: SAFE-BOOT-COUNTER
    #[test]
    fn counts_up_across_page_switches() {
        let mut m = Model::new(6, 1);
        for n in 1..=40u32 {
            m.boot(None);
            assert_eq!(advance(&mut m), Ok(n));
            assert_eq!(value(&mut m), Ok(n));
        }
        // 3 entries a page: boot 40 is the first entry of page 1
        // ((40 - 1) / 3 = 13, odd; (40 - 1) % 3 = 0).
        assert_eq!(m.pages[1][0], Cell::Good(40));
        assert_eq!(m.pages[1][1], Cell::Good(!40));
    }

    /// A region the flash will not write (QEMU's netduinoplus2: its flash
    /// is read-only and its controller ignores every command), one that
    /// reports a failed program, one that cannot be read: each a typed
    /// refusal, never a value.
    ///
    /// Verifies: SAFE-BOOT-COUNTER
    #[test]
    fn a_failed_write_gives_no_value() {
        let mut m = Model::new(8, 2);
        m.read_only = true;
        assert_eq!(
            advance(&mut m),
            Err(BootCounterError::Verify {
                expected: 1,
                read: ERASED
            })
        );
        // A program that does not take: the attempt fails to read back,
        // and the next attempt (no whole entry anywhere, nothing to keep)
        // erases the page and writes it again.
        let mut m = Model::new(8, 2);
        m.boot(Some((25, Fault::Ignore)));
        assert_eq!(advance(&mut m), Ok(1));
        assert_eq!(m.pages[0][0], Cell::Good(1));
        assert_eq!(m.pages[0][1], Cell::Good(!1));
        let mut m = Model::new(8, 2);
        m.boot(Some((26, Fault::Fail)));
        assert_eq!(
            advance(&mut m),
            Err(BootCounterError::ProgramFailed { page: 0, word: 1 })
        );
        m.boot(Some((3, Fault::Unreadable)));
        assert_eq!(
            advance(&mut m),
            Err(BootCounterError::Unreadable { page: 0, word: 3 })
        );
        // After the failures, a good boot carries on above every value
        // the region may hold.
        m.boot(None);
        let v = advance(&mut m).unwrap();
        assert!(v >= 1);
        // Zeroed memory (QEMU's code memory where no image was loaded):
        // no whole entry, page 0 erased, then 1.
        let mut z = Model::new(8, 3);
        z.pages[0].fill(Cell::Good(0));
        z.pages[1].fill(Cell::Good(0));
        assert_eq!(advance(&mut z), Ok(1));
        let mut g = Model::new(1, 3);
        assert_eq!(
            advance(&mut g),
            Err(BootCounterError::Geometry { page_words: 1 })
        );
    }

    /// An erase that leaves the page unerased is refused before anything
    /// is written into it.
    ///
    /// Verifies: SAFE-BOOT-COUNTER
    #[test]
    fn an_erase_that_does_not_erase_is_refused() {
        let mut m = Model::new(4, 4);
        for n in 1..=2 {
            m.boot(None);
            assert_eq!(advance(&mut m), Ok(n));
        }
        // Page 0 is full (2 entries), page 1 gets 3..4, then page 0 is
        // erased for 5: that erase is ignored.
        for n in 3..=4 {
            m.boot(None);
            assert_eq!(advance(&mut m), Ok(n));
        }
        m.boot(Some((16, Fault::Ignore)));
        assert_eq!(
            advance(&mut m),
            Err(BootCounterError::EraseVerify {
                page: 0,
                word: 0,
                value: 1
            })
        );
        assert_eq!(value(&mut m), Ok(4));
    }

    /// A program that reports success and stores other bits, and one
    /// whose cell reads back right and then, at a later read, with a bit
    /// flipped: each is a failed write, the value is written again in the
    /// next entry (here on the other page), and the boot's value is stored
    /// durably; the entry left behind never reads whole. A weak cell that
    /// flips at the second or the last of the [`READS`] reads is caught.
    ///
    /// Verifies: SAFE-BOOT-COUNTER
    #[test]
    fn a_write_that_does_not_read_back_steadily_is_a_failed_write() {
        // Pages of 2 entries; boot 1 wrote entry 0 of page 0. Boot 2 scans
        // 2 x 2 entries (operations 0-7, one read a word), then programs
        // entry 1 of page 0: its first word is operation 8.
        let mut before = Model::new(4, 6);
        before.boot(None);
        assert_eq!(advance(&mut before), Ok(1));
        let ops_boot = 8;
        for fault in [Fault::Corrupt, Fault::Weak(1), Fault::Weak(READS - 1)] {
            let mut m = Model::new(4, 6);
            m.pages = before.pages.clone();
            m.boot(Some((ops_boot, fault)));
            let v = advance(&mut m).unwrap();
            assert_eq!(v, 2, "{fault:?}");
            assert!(m.holds_durably(2), "{fault:?}: {:?}", m.pages);
            // Entry 1 of page 0 was the failed write: not whole, not
            // erased; the value went above it (page 1, the page switch).
            let a = m.read_cell(0, 2).unwrap();
            let b = m.read_cell(0, 3).unwrap();
            assert_eq!(decode(a, b), None, "{fault:?}");
            assert_eq!(value(&mut m), Ok(2));
            m.boot(None);
            assert_eq!(advance(&mut m), Ok(3));
        }
    }

    /// The top of the range is refused, not wrapped.
    ///
    /// Verifies: SAFE-BOOT-COUNTER
    #[test]
    fn the_top_of_the_range_is_refused() {
        let mut m = Model::new(4, 5);
        m.pages[0][0] = Cell::Good(ERASED - 1);
        m.pages[0][1] = Cell::Good(!(ERASED - 1));
        assert_eq!(advance(&mut m), Err(BootCounterError::Exhausted));
    }

    /// One step of a boot sequence: how this boot's flash faults.
    fn boot_fault() -> impl proptest::strategy::Strategy<Value = Option<(usize, Fault)>> {
        use proptest::prelude::*;
        prop_oneof![
            3 => Just(None),
            4 => (0usize..40).prop_map(|at| Some((at, Fault::Cut))),
            1 => (0usize..40).prop_map(|at| Some((at, Fault::Fail))),
            1 => (0usize..40).prop_map(|at| Some((at, Fault::Unreadable))),
            1 => (0usize..40).prop_map(|at| Some((at, Fault::Corrupt))),
            1 => (0usize..40, 1..READS).prop_map(|(at, n)| Some((at, Fault::Weak(n)))),
        ]
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(5000))]
        /// Random sequences of boots on small pages (many page switches),
        /// each boot cut by a power loss at any operation (a torn program
        /// or erase, marginal cells read differently every time), or
        /// faulted (a program or erase that reports failure having torn
        /// its cells, an unreadable word, a program that reports success
        /// and stores other bits, one whose cell reads right and then with
        /// a bit flipped), or clean: the value a completed boot returns is
        /// strictly greater than at every earlier completed boot (so it
        /// never repeats) and stored in cells that read it steadily
        /// (durably written), and a clean boot always completes.
        ///
        /// Verifies: SAFE-BOOT-COUNTER
        #[test]
        fn a_boot_value_never_repeats_across_cuts_and_faults(
            entries in 1usize..5,
            seed in proptest::prelude::any::<u64>(),
            boots in proptest::collection::vec(boot_fault(), 1..120),
        ) {
            let mut m = Model::new(2 * entries, seed);
            let mut last: Option<u32> = None;
            for f in boots {
                m.boot(f);
                match advance(&mut m) {
                    Ok(v) => {
                        if let Some(l) = last {
                            proptest::prop_assert!(v > l, "{v} after {l}");
                        }
                        proptest::prop_assert!(m.holds_durably(v), "{v} not durable: {:?}", m.pages);
                        last = Some(v);
                    }
                    Err(e) => {
                        proptest::prop_assert!(f.is_some(), "a clean boot failed: {e:?}");
                    }
                }
            }
        }
    }
}
