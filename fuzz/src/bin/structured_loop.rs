//! The structured fuzz target (`raim_fuzz::run`) on stable Rust, without
//! libFuzzer (no nightly or cargo-fuzz needed): each iteration draws
//! 16-512 bytes from a seeded SplitMix64 stream, builds a `Scenario` from
//! them with `arbitrary`, runs it and checks the invariants. No coverage
//! feedback: a random search over the structured space.
//!
//! `cd fuzz && cargo run --release --bin structured_loop -- 10000000 1`
//! (iterations, seed). Exits 1 on the first broken invariant, printing the
//! iteration and the scenario.

use std::time::Instant;

use arbitrary::{Arbitrary, Unstructured};
use raim_fuzz::{run, Scenario, Tally};

fn splitmix(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let iterations: u64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(100_000);
    let seed: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1);
    let mut state = seed;
    let mut tally = Tally::default();
    let mut bytes = Vec::with_capacity(512);
    let t0 = Instant::now();
    for i in 0..iterations {
        let len = 16 + (splitmix(&mut state) % 497) as usize;
        bytes.clear();
        while bytes.len() < len {
            bytes.extend_from_slice(&splitmix(&mut state).to_le_bytes());
        }
        bytes.truncate(len);
        let Ok(scenario) = Scenario::arbitrary(&mut Unstructured::new(&bytes)) else {
            continue;
        };
        if let Err(e) = run(&scenario, &mut tally) {
            eprintln!("iteration {i} (seed {seed}): {e}\n{scenario:?}");
            std::process::exit(1);
        }
        if (i + 1) % 1_000_000 == 0 {
            eprintln!(
                "{} iterations, {:.0} s: {tally:?}",
                i + 1,
                t0.elapsed().as_secs_f64()
            );
        }
    }
    println!(
        "{iterations} iterations (seed {seed}) in {:.0} s, no invariant broken: {tally:?}",
        t0.elapsed().as_secs_f64()
    );
}
