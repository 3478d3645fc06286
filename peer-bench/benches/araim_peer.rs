//! Side by side, in one criterion run: raim-core's ARAIM against the peer
//! crate sidereon-core 3.0.6 (`araim::araim`), on the inputs of
//! raim-core's own ARAIM bench (ADD v3.0 App. D; 20 and 30 satellites).
//! Run (not part of scripts/test.sh): cd peer-bench && cargo bench --bench araim_peer
//!
//! The peer takes ECEF lines of sight and a receiver position: the
//! receiver is put at latitude 0, longitude 0, and each ENU geometry row
//! (minus the line of sight) is rotated into ECEF, as the peer's own
//! App. D test does; C_int and C_acc are given to both as effective
//! sigmas, so neither applies its elevation model.

#[path = "../../crates/raim-core/benches/common/araim_inputs.rs"]
mod araim_inputs;

#[path = "araim_peer_common.rs"]
mod araim_peer_common;

use araim_inputs::{appendix_d, sky};
use araim_peer_common::peer_inputs;
use criterion::{criterion_group, criterion_main, Criterion};
use raim_core::araim::{Araim, AraimConfig, Ism};
use raim_core::System;
use sidereon_core::araim as peer;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let cfg = AraimConfig::default();
    let alloc = peer::IntegrityAllocation::lpv_200();
    let ge = [System::Gps, System::Galileo];
    let mut engine = Box::new(Araim::<f64, 32, 1024>::new());
    let cases = [
        ("appendix_d", appendix_d(), 1e-4),
        ("sky20_psat1e-5_pconst1e-4", sky(10, 1e-5), 1e-4),
        ("sky30_psat1e-4_pconst1e-8", sky(15, 1e-4), 1e-8),
        ("sky30_psat1e-4_pconst1e-4", sky(15, 1e-4), 1e-4),
    ];
    for (name, sats, p_const) in cases.iter() {
        let ism = Ism::with(&ge, *p_const);
        let ours = engine.process(&cfg, &ism, sats).unwrap();
        let (geo, pism) = peer_inputs(sats, *p_const);
        let theirs = peer::araim(&geo, &pism, &alloc);
        eprintln!(
            "{name}: ours {} modes, VPL {:.3} (ADD {:.3}), HPL {:.3} (ADD {:.3}), EMT {:.3}, p_unmon {:.3e}, unavailable {:?}",
            ours.modes.len(),
            ours.pl_exact.vpl_m,
            ours.pl_add.vpl_m,
            ours.pl_exact.hpl_m,
            ours.pl_add.hpl_m,
            ours.emt_m,
            ours.p_unmon,
            ours.unavailable
        );
        match theirs {
            Ok(t) => eprintln!(
                "{name}: peer {} modes, VPL {:.3}, HPL {:.3}, EMT {:.3}, p_unmon {:.3e}, available {}",
                t.fault_modes.len() - 1,
                t.vpl_m,
                t.hpl_m,
                t.emt_m,
                t.p_unmonitored,
                t.available
            ),
            Err(e) => eprintln!("{name}: peer error {e:?}"),
        }
    }
    let mut group = c.benchmark_group("araim_side_by_side");
    for (name, sats, p_const) in cases.iter() {
        let ism = Ism::with(&ge, *p_const);
        group.bench_function(format!("raim-core/{name}"), |b| {
            b.iter(|| {
                let out = engine
                    .process(black_box(&cfg), black_box(&ism), black_box(sats))
                    .unwrap();
                black_box(out.pl_add.vpl_m)
            })
        });
        let (geo, pism) = peer_inputs(sats, *p_const);
        group.bench_function(format!("sidereon-core-3.0.6/{name}"), |b| {
            b.iter(|| black_box(peer::araim(black_box(&geo), black_box(&pism), black_box(&alloc))))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
