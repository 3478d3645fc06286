//! ARAIM epochs: ADD v3.0 Appendix D (10 satellites, 12 modes),
//! and 30 satellites G15 + E15 with P_sat 1e-4 (satellite pairs) at
//! P_const 1e-8 and 1e-4 (satellite + constellation modes).
//! Each case also with 30 m on its first satellite, then FDE (`+fde`).
//! Run: cargo bench -p raim-core --bench araim
//! The same inputs run through the peer crate in peer-bench/ (benches/araim_peer.rs).

use criterion::{criterion_group, criterion_main, Criterion};
#[path = "common/araim_inputs.rs"]
mod araim_inputs;

use araim_inputs::{appendix_d, sky};
use raim_core::araim::{Araim, AraimConfig, Ism};
use raim_core::System;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let cfg = AraimConfig::default();
    let ge = [System::Gps, System::Galileo];
    let mut engine = Box::new(Araim::<f64, 32, 1024>::new());
    let cases = [
        ("appendix_d", appendix_d(), Ism::with(&ge, 1e-4)),
        (
            "sky20_psat1e-5_pconst1e-4",
            sky(10, 1e-5),
            Ism::with(&ge, 1e-4),
        ),
        (
            "sky30_psat1e-4_pconst1e-8",
            sky(15, 1e-4),
            Ism::with(&ge, 1e-8),
        ),
        (
            "sky30_psat1e-4_pconst1e-4",
            sky(15, 1e-4),
            Ism::with(&ge, 1e-4),
        ),
    ];
    for (name, sats, ism) in cases.iter() {
        let out = engine.process(&cfg, ism, sats).unwrap();
        eprintln!(
            "{name}: {} modes, VPL {:.3} m, HPL {:.3} m, EMT {:.3} m, available {:?}",
            out.modes.len(),
            out.pl_exact.vpl_m,
            out.pl_exact.hpl_m,
            out.emt_m,
            out.unavailable
        );
    }
    let mut group = c.benchmark_group("araim");
    for (name, sats, ism) in cases.iter() {
        group.bench_function(*name, |b| {
            b.iter(|| {
                let out = engine
                    .process(black_box(&cfg), black_box(ism), black_box(sats))
                    .unwrap();
                black_box(out.pl_add.vpl_m)
            })
        });
    }
    // After a detection: 30 m on the first satellite, process + FDE (the
    // tests-only check of every single-event candidate, then the chosen
    // subset with its exclusion-risk PLs).
    let mut scratch = Box::new(Araim::<f64, 32, 1024>::new());
    for (name, sats, ism) in cases.iter() {
        let mut faulted = sats.clone();
        faulted[0].residual_m = 30.0;
        group.bench_function(format!("{name}+fde"), |b| {
            b.iter(|| {
                engine
                    .process(black_box(&cfg), black_box(ism), black_box(&faulted))
                    .unwrap();
                black_box(engine.fde(&cfg, ism, &faulted, &mut scratch).unwrap())
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
