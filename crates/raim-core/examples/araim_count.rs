//! Runs one ARAIM bench case `iters` times, for instruction counts that
//! do not depend on the machine's load:
//!   perf stat -e instructions:u target/release/examples/araim_count <case> <iters>
//! (cost per epoch = (count at iters - count at 0) / iters). Cases: the
//! inputs of benches/araim.rs: appendix_d, sky20, sky30_pconst1e-8,
//! sky30_pconst1e-4; `<case>+fde`: 30 m on the first satellite, then FDE;
//! `<case>+fde2`: also -30 m on the last one (a second constellation on the
//! skies), so that no single event is consistent and FDE searches the
//! multi-event candidates.

#[path = "../benches/common/araim_inputs.rs"]
mod araim_inputs;

use araim_inputs::{appendix_d, sky};
use raim_core::araim::{Araim, AraimConfig, Ism};
use raim_core::System;
use std::hint::black_box;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let case = args.get(1).map(String::as_str).unwrap_or("appendix_d");
    let iters: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1000);
    let ge = [System::Gps, System::Galileo];
    let (sats, p_const) = match case.trim_end_matches("+fde2").trim_end_matches("+fde") {
        "appendix_d" => (appendix_d(), 1e-4),
        "sky20" => (sky(10, 1e-5), 1e-4),
        "sky30_pconst1e-8" => (sky(15, 1e-4), 1e-8),
        "sky30_pconst1e-4" => (sky(15, 1e-4), 1e-4),
        other => panic!("unknown case {other}"),
    };
    // `<case>+fde`: 30 m on the first satellite, then FDE (the
    // consistency check of every single-event candidate).
    let fde2 = case.ends_with("+fde2");
    let fde = fde2 || case.ends_with("+fde");
    let mut sats = sats;
    if fde {
        sats[0].residual_m = 30.0;
    }
    if fde2 {
        if let Some(last) = sats.last_mut() {
            last.residual_m = -30.0;
        }
    }
    let ism = Ism::with(&ge, p_const);
    let mut scratch = Box::new(Araim::<f64, 32, 1024>::new());
    let cfg = AraimConfig::default();
    let mut engine = Box::new(Araim::<f64, 32, 1024>::new());
    let mut acc = 0.0;
    for _ in 0..iters {
        let out = engine
            .process(black_box(&cfg), black_box(&ism), black_box(&sats))
            .unwrap();
        acc += out.pl_add.vpl_m;
        if fde {
            let d = engine
                .fde(black_box(&cfg), &ism, &sats, &mut scratch)
                .unwrap();
            acc += matches!(d, raim_core::araim::FdeDecision::Excluded { .. }) as u8 as f64;
            if iters == 1 {
                println!("{d:?}");
            }
        }
    }
    let out = engine.process(&cfg, &ism, &sats).unwrap();
    println!(
        "{case}: {} modes, VPL {:.3} m, HPL {:.3} m ({acc})",
        out.modes.len(),
        out.pl_exact.vpl_m,
        out.pl_exact.hpl_m
    );
}
