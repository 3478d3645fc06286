//! One engine on one epoch, repeated, for callgrind instruction counts:
//! `cargo build --release --example peer_cost`, then `valgrind
//! --tool=callgrind --callgrind-out-file=/dev/null
//! target/release/examples/peer_cost ENGINE N FAULT_M REPS` with ENGINE
//! `raim` or `sidereon`; per epoch = (total(REPS) - total(0)) / REPS.

use peer_bench::{peer_options, peer_rows, sky};
use raim_core::{Config, Epoch, Raim};
use std::hint::black_box;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let engine = a.get(1).map(String::as_str).unwrap_or("raim");
    let n: usize = a.get(2).and_then(|v| v.parse().ok()).unwrap_or(20);
    let fault_m: f64 = a.get(3).and_then(|v| v.parse().ok()).unwrap_or(0.0);
    let reps: usize = a.get(4).and_then(|v| v.parse().ok()).unwrap_or(100);
    let sats = sky(n, fault_m);
    let rows = peer_rows(&sats);
    let cfg = Config::default();
    let opts = peer_options();
    let mut raim = Raim::<32>::new();
    let epoch = Epoch::linear(0.0, &sats);
    // The first run (raim-core's threshold cache) is in both totals.
    let first = raim.process(&cfg, &epoch).expect("raim");
    let peer = sidereon_core::quality::raim_fde_design(&rows, &opts).expect("peer");
    for _ in 0..reps {
        if engine == "raim" {
            let _ = black_box(raim.process(black_box(&cfg), black_box(&epoch)));
        } else {
            let _ = black_box(sidereon_core::quality::raim_fde_design(
                black_box(&rows),
                black_box(&opts),
            ));
        }
    }
    eprintln!(
        "n={n} fault={fault_m}: raim-core {:?} excl {:?}; peer excluded {:?}",
        first.decision,
        first
            .exclusions
            .iter()
            .map(|e| e.id.to_string())
            .collect::<Vec<_>>(),
        peer.excluded
    );
}
