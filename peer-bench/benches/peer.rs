//! raim-core against sidereon-core 3.0.6 on the same linearised rows, in
//! one run (issue 10): `cd peer-bench && cargo bench --bench peer`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use peer_bench::{peer_options, peer_rows, sky};
use raim_core::{Config, Epoch, Raim};
use sidereon_core::quality::raim_fde_design;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let cfg = Config::default();
    let opts = peer_options();
    let mut group = c.benchmark_group("peer");
    for n in [8usize, 12, 20, 32] {
        for (label, fault) in [("clean", 0.0), ("fault50m", 50.0)] {
            let sats = sky(n, fault);
            let rows = peer_rows(&sats);
            let mut raim = Raim::<32>::new();
            let _ = raim.process(&cfg, &Epoch::linear(0.0, &sats));
            group.bench_with_input(
                BenchmarkId::new(format!("raim-core/{label}"), n),
                &sats,
                |b, s| b.iter(|| raim.process(black_box(&cfg), black_box(&Epoch::linear(0.0, s)))),
            );
            group.bench_with_input(
                BenchmarkId::new(format!("sidereon/{label}"), n),
                &rows,
                |b, r| b.iter(|| raim_fde_design(black_box(r), black_box(&opts))),
            );
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
