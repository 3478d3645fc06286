//! The f32/f64 equivalence suite, full form: every replay case
//! over its whole file, the committed vectors, and a seeded Monte Carlo of
//! `EPOCHS` epochs (default 10^6), each through `Raim::<N, f32>` and
//! `Raim::<N, f64>`. Prints the Markdown report committed in
//! docs/F32_EQUIVALENCE.md:
//!
//!     cargo run --release -p host-tests --example f32_equivalence [EPOCHS] [SEED]

#[path = "../tests/equivalence_common/mod.rs"]
mod equivalence_common;

use equivalence_common::*;

fn main() {
    let mut args = std::env::args().skip(1);
    let epochs: u64 = args.next().map_or(1_000_000, |a| a.parse().unwrap());
    let seed: u64 = args.next().map_or(1, |a| a.parse().unwrap());
    let started = std::time::Instant::now();
    let mut tallies = Vec::new();
    for case in replay_cases() {
        let t = run_replay(&case);
        eprintln!("{} ({:.0} s)", t.row(), started.elapsed().as_secs_f64());
        tallies.push(t);
    }
    tallies.push(run_vectors());
    // The Monte Carlo in chunks on two threads (the machine's cores).
    let chunk = epochs.div_ceil(2);
    let handles: Vec<_> = (0..2u64)
        .map(|k| {
            let range = (k * chunk)..((k + 1) * chunk).min(epochs);
            std::thread::spawn(move || run_monte_carlo(seed, range))
        })
        .collect();
    let mut mc = Tally::new(&format!("Monte Carlo, seed {seed}, {epochs} epochs"));
    for h in handles {
        mc.merge(&h.join().unwrap());
    }
    eprintln!("{} ({:.0} s)", mc.row(), started.elapsed().as_secs_f64());
    tallies.push(mc);
    println!("{}", report(&tallies));
    println!(
        "(run time {:.0} s, `cargo run --release -p host-tests --example f32_equivalence {epochs} {seed}`)",
        started.elapsed().as_secs_f64()
    );
}
