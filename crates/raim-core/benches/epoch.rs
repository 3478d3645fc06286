//! One epoch (snapshot test + L-RAIM FDE + protection levels) at n = 8, 12,
//! 20, 32 satellites, clean and with a 50 m step on one satellite.
//! Run: cargo bench -p raim-core --bench epoch

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use raim_core::{Config, Epoch, LinearObservation, Raim, SatId, System};
use std::hint::black_box;

/// n satellites on a golden-angle spiral in azimuth, elevations 10..85 deg,
/// unit sigma, deterministic pseudo-noise.
fn sky(n: usize, fault_m: f64) -> Vec<LinearObservation> {
    (0..n)
        .map(|i| {
            let az = (i as f64 * 137.507_764_f64).rem_euclid(360.0);
            let el = 10.0 + 75.0 * ((i * 7) % n) as f64 / n as f64;
            let noise = ((i as f64 * 12.9898).sin() * 43758.5453).fract() - 0.5;
            let r = noise + if i == 2 { fault_m } else { 0.0 };
            let mut o = LinearObservation::from_az_el(
                SatId::new(
                    if i % 2 == 0 {
                        System::Gps
                    } else {
                        System::Galileo
                    },
                    i as u8 + 1,
                ),
                az.to_radians(),
                el.to_radians(),
                r,
            );
            o.sigma_m = Some(1.0);
            o
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let cfg = Config::default();
    let mut group = c.benchmark_group("epoch");
    for n in [8usize, 12, 20, 32] {
        for (label, fault) in [("clean", 0.0), ("fault50m", 50.0)] {
            let sats = sky(n, fault);
            let mut raim = Raim::<32>::new();
            // Warm the threshold cache, as in steady state.
            let _ = raim.process(&cfg, &Epoch::linear(0.0, &sats));
            group.bench_with_input(BenchmarkId::new(label, n), &sats, |b, sats| {
                b.iter(|| raim.process(black_box(&cfg), black_box(&Epoch::linear(0.0, sats))))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
