//! The STM32F4 RNG's draw procedure (firmware `board/rng_draw.rs`, the
//! same source) against a model of the RNG's registers: each of the
//! reference manual's rules (RM0090 §24.3) shown to hold, and every way
//! the draw can fail shown to end in `None` within its budget, with the
//! RNG left disabled. QEMU's netduinoplus2 does not model the RNG, so this
//! is where the paths other than "no clock" are exercised.

#[allow(dead_code)]
#[path = "../../firmware/src/board/rng_draw.rs"]
mod rng_draw;

use rng_draw::{draw, RngRegs, SEED_RESTARTS, SR_CECS, SR_CEIS, SR_DRDY, SR_SECS, SR_SEIS, WORDS};

/// Status reads each word may wait in these tests.
const BUDGET_READS: u32 = 50;

/// What the model's next status reads show before a word is ready.
#[derive(Clone, Copy)]
enum Event {
    /// The word is ready after this many reads without DRDY.
    Word(u32),
    /// SECS (and SEIS) set until the RNG is restarted.
    SeedError,
    /// CECS (and CEIS) set.
    ClockError,
    /// DRDY never sets.
    Never,
    /// DRDY with the word, then SECS raised while it is read.
    SeedErrorDuringRead,
}

/// The RNG as the draw sees it: a script of events, a counter as the
/// words, and a log of what was done to it.
struct Model {
    events: std::collections::VecDeque<Event>,
    /// Reads left before DRDY, for the current word.
    wait: Option<u32>,
    sr: u32,
    next_word: u32,
    /// A value returned twice in a row when set (a stuck source).
    stuck: Option<u32>,
    enabled: bool,
    enables: u32,
    status_reads: u32,
    words_read: u32,
    /// True while RNGEN is clear: reading data then is a fault of the draw.
    read_while_disabled: bool,
}

impl Model {
    fn new(events: &[Event]) -> Self {
        Model {
            events: events.iter().copied().collect(),
            wait: None,
            sr: 0,
            next_word: 0x1234_5678,
            stuck: None,
            enabled: false,
            enables: 0,
            status_reads: 0,
            words_read: 0,
            read_while_disabled: false,
        }
    }
    /// Every word ready at once, for `n` words.
    fn healthy(n: usize) -> Self {
        Model::new(&vec![Event::Word(0); n])
    }
}

impl RngRegs for Model {
    fn status(&mut self) -> u32 {
        self.status_reads += 1;
        if !self.enabled {
            return self.sr & !SR_DRDY;
        }
        if self.sr & (SR_DRDY | SR_SECS | SR_CECS) != 0 {
            return self.sr;
        }
        if self.wait.is_none() {
            match self.events.pop_front().unwrap_or(Event::Never) {
                Event::Word(n) => self.wait = Some(n),
                Event::SeedError => self.sr |= SR_SECS | SR_SEIS,
                Event::ClockError => self.sr |= SR_CECS | SR_CEIS,
                Event::Never => self.wait = Some(u32::MAX),
                Event::SeedErrorDuringRead => {
                    self.sr |= SR_DRDY;
                    self.events.push_front(Event::SeedError);
                    return self.sr;
                }
            }
        }
        if let Some(n) = self.wait {
            if n == 0 {
                self.wait = None;
                self.sr |= SR_DRDY;
            } else {
                self.wait = Some(n - 1);
            }
        }
        self.sr
    }
    fn data(&mut self) -> u32 {
        if !self.enabled {
            self.read_while_disabled = true;
        }
        self.words_read += 1;
        self.sr &= !SR_DRDY;
        if matches!(self.events.front(), Some(Event::SeedError)) {
            self.events.pop_front();
            self.sr |= SR_SECS | SR_SEIS;
        }
        match self.stuck {
            Some(w) => w,
            None => {
                self.next_word = self
                    .next_word
                    .wrapping_mul(1_664_525)
                    .wrapping_add(1_013_904_223);
                self.next_word
            }
        }
    }
    fn set_enabled(&mut self, on: bool) {
        if on && !self.enabled {
            self.enables += 1;
            // A restart clears the current seed error (RM0090 §24.3.2).
            self.sr &= !(SR_SECS | SR_DRDY);
            self.wait = None;
        }
        self.enabled = on;
    }
    fn clear_errors(&mut self) {
        self.sr &= !(SR_SEIS | SR_CEIS);
    }
}

/// The words a healthy RNG gives, in order, after the discarded first.
fn expected(skip: usize) -> Vec<u8> {
    let mut m = Model::healthy(64);
    m.enabled = true;
    (0..skip + 1 + WORDS)
        .map(|_| m.data())
        .skip(skip + 1)
        .flat_map(u32::to_le_bytes)
        .collect()
}

/// Verifies: SAFE-RNG
#[test]
fn a_healthy_rng_gives_eight_words_after_the_discarded_first() {
    let mut m = Model::healthy(64);
    let got = draw(&mut m, BUDGET_READS).unwrap();
    assert_eq!(got.to_vec(), expected(0));
    assert_eq!(m.words_read, 1 + WORDS as u32);
    assert_eq!((m.enables, m.enabled), (1, false));
    assert!(!m.read_while_disabled);
    // Slow words within the budget are waited for.
    let mut slow = Model::new(&[Event::Word(BUDGET_READS - 2); 9]);
    assert_eq!(draw(&mut slow, BUDGET_READS).unwrap().to_vec(), expected(0));
}

#[test]
fn a_seed_error_discards_the_draw_and_restarts_it() {
    // Three good words, then a seed error: those words are not used.
    let mut events = vec![Event::Word(0); 3];
    events.push(Event::SeedError);
    events.extend(vec![Event::Word(0); 9]);
    let mut m = Model::new(&events);
    let got = draw(&mut m, BUDGET_READS).unwrap();
    assert_eq!(got.to_vec(), expected(3));
    assert_eq!((m.enables, m.enabled), (2, false));
    // An error flagged while a word is read: that word is not used either.
    let mut events = vec![Event::Word(0); 4];
    events.push(Event::SeedErrorDuringRead);
    events.extend(vec![Event::Word(0); 9]);
    let mut m = Model::new(&events);
    let got = draw(&mut m, BUDGET_READS).unwrap();
    assert_eq!(got.to_vec(), expected(5));
    assert_eq!(m.enables, 2);
    // On the last word, where no later status read would see the flag.
    let mut events = vec![Event::Word(0); WORDS];
    events.push(Event::SeedErrorDuringRead);
    events.extend(vec![Event::Word(0); 9]);
    let mut m = Model::new(&events);
    let got = draw(&mut m, BUDGET_READS).unwrap();
    assert_eq!(got.to_vec(), expected(WORDS + 1));
    assert_eq!(m.enables, 2);
}

/// Verifies: SAFE-RNG
#[test]
fn repeated_seed_errors_give_none_after_the_allowed_restarts() {
    let mut m = Model::new(&[Event::SeedError; 16]);
    assert_eq!(draw(&mut m, BUDGET_READS), None);
    assert_eq!((m.enables, m.enabled), (SEED_RESTARTS + 1, false));
    assert_eq!(m.words_read, 0);
    // One fewer than the limit still succeeds.
    let mut events = vec![Event::SeedError; SEED_RESTARTS as usize];
    events.extend(vec![Event::Word(0); 9]);
    let mut m = Model::new(&events);
    assert!(draw(&mut m, BUDGET_READS).is_some());
}

#[test]
fn a_clock_error_gives_none() {
    for at in [0, 1, 5] {
        let mut events = vec![Event::Word(0); at];
        events.push(Event::ClockError);
        events.extend(vec![Event::Word(0); 9]);
        let mut m = Model::new(&events);
        assert_eq!(draw(&mut m, BUDGET_READS), None, "clock error at word {at}");
        assert_eq!((m.enables, m.enabled), (1, false));
        assert_eq!(m.words_read, at as u32);
    }
}

/// QEMU's case: DRDY never sets (the registers read 0). The draw ends
/// after one word's budget of status reads.
#[test]
fn drdy_that_never_sets_gives_none_within_the_budget() {
    let mut m = Model::new(&[]);
    assert_eq!(draw(&mut m, BUDGET_READS), None);
    assert_eq!(m.status_reads, BUDGET_READS);
    assert_eq!((m.words_read, m.enabled), (0, false));
    // A word slower than the budget, after some good ones.
    let mut events = vec![Event::Word(0); 4];
    events.push(Event::Word(BUDGET_READS));
    let mut m = Model::new(&events);
    assert_eq!(draw(&mut m, BUDGET_READS), None);
}

/// The continuous test: a word equal to the one before it fails the draw.
#[test]
fn a_repeated_word_gives_none() {
    let mut m = Model::healthy(64);
    m.stuck = Some(0xDEAD_BEEF);
    assert_eq!(draw(&mut m, BUDGET_READS), None);
    assert_eq!(m.words_read, 2);
    assert!(!m.enabled);
}
