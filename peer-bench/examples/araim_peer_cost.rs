//! One ARAIM engine on one case, repeated, for callgrind instruction
//! counts beside the peer (load-independent):
//! `cargo build --release --example araim_peer_cost`, then
//! `valgrind --tool=callgrind --callgrind-out-file=/dev/null
//! target/release/examples/araim_peer_cost ENGINE CASE REPS` with ENGINE
//! `raim` or `sidereon` and CASE `appendix_d`, `sky20`, `sky30_pconst1e-8`,
//! `sky30_pconst1e-4`; per epoch = (total(REPS) - total(0)) / REPS.

#[path = "../../crates/raim-core/benches/common/araim_inputs.rs"]
mod araim_inputs;
#[path = "../benches/araim_peer_common.rs"]
mod araim_peer_common;

use araim_inputs::{appendix_d, sky};
use araim_peer_common::peer_inputs;
use raim_core::araim::{Araim, AraimConfig, Ism};
use raim_core::System;
use sidereon_core::araim as peer;
use std::hint::black_box;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let engine = a.get(1).map(String::as_str).unwrap_or("raim");
    let case = a.get(2).map(String::as_str).unwrap_or("appendix_d");
    let reps: usize = a.get(3).and_then(|v| v.parse().ok()).unwrap_or(100);
    let (sats, p_const) = match case {
        "appendix_d" => (appendix_d(), 1e-4),
        "sky20" => (sky(10, 1e-5), 1e-4),
        "sky30_pconst1e-8" => (sky(15, 1e-4), 1e-8),
        "sky30_pconst1e-4" => (sky(15, 1e-4), 1e-4),
        other => panic!("unknown case {other}"),
    };
    let ism = Ism::with(&[System::Gps, System::Galileo], p_const);
    let cfg = AraimConfig::default();
    let alloc = peer::IntegrityAllocation::lpv_200();
    let (geo, pism) = peer_inputs(&sats, p_const);
    let mut raim = Box::new(Araim::<f64, 32, 1024>::new());
    let mut acc = 0.0;
    for _ in 0..reps {
        if engine == "raim" {
            acc += raim
                .process(black_box(&cfg), black_box(&ism), black_box(&sats))
                .expect("raim")
                .pl_add
                .vpl_m;
        } else {
            acc += peer::araim(black_box(&geo), black_box(&pism), black_box(&alloc))
                .map(|o| o.vpl_m)
                .unwrap_or(0.0);
        }
    }
    println!("{engine} {case} {reps}: {acc}");
}
