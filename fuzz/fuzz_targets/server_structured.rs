//! Structured fuzzing of the protocol server (`raim_fuzz::run`): sequences
//! of valid requests (epochs, configurations, locks) and the invariants
//! after every answer.
//!
//! `cd fuzz && cargo +nightly fuzz run server_structured -- -runs=10000000`
#![no_main]

use libfuzzer_sys::fuzz_target;
use raim_fuzz::{run, Scenario, Tally};

fuzz_target!(|scenario: Scenario| {
    if let Err(e) = run(&scenario, &mut Tally::default()) {
        panic!("{e}\n{scenario:?}");
    }
});
