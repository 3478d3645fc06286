//! One epoch through `Raim::process` with the reconstruction FDE (SPEC §8,
//! docs/MULTIFAULT.md) at n = 12, 20, 32 satellites (GPS + Galileo) with t
//! = 1, 2, 3 simultaneous 60 m faults and t_max = t: detection, the group
//! search, the decision, the exclusion's re-solve and the protection
//! levels; and the same epoch through today's FDE for comparison.
//! Run: cargo bench -p raim-core --bench multifault

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use raim_core::{Config, Epoch, FdeMethod, LinearObservation, Raim, SatId, System};
use std::hint::black_box;

/// As benches/epoch.rs: a golden-angle spiral, elevations 10..85 deg, unit
/// sigma, deterministic pseudo-noise; 60 m on rows 2, 5, 9 (the first t).
fn sky(n: usize, t: usize) -> Vec<LinearObservation> {
    let faulty = [2usize, 5, 9];
    (0..n)
        .map(|i| {
            let az = (i as f64 * 137.507_764_f64).rem_euclid(360.0);
            let el = 10.0 + 75.0 * ((i * 7) % n) as f64 / n as f64;
            let noise = ((i as f64 * 12.9898).sin() * 43758.5453).fract() - 0.5;
            let fault = if faulty[..t].contains(&i) { 60.0 } else { 0.0 };
            let sys = if i % 2 == 0 {
                System::Gps
            } else {
                System::Galileo
            };
            let mut o = LinearObservation::from_az_el(
                SatId::new(sys, i as u8 + 1),
                az.to_radians(),
                el.to_radians(),
                noise + fault,
            );
            o.sigma_m = Some(1.0);
            o
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("multifault");
    for n in [12usize, 20, 32] {
        for t in 1..=3u8 {
            let sats = sky(n, usize::from(t));
            let epoch = Epoch::linear(0.0, &sats);
            let rec = Config {
                fde_method: FdeMethod::Reconstruction {
                    t_max: t,
                    group_budget: 1000,
                },
                max_exclusions: 3,
                ..Config::default()
            };
            let seq = Config {
                max_exclusions: 3,
                ..Config::default()
            };
            let mut raim = Raim::<32>::new();
            let r = raim.process(&rec, &epoch).unwrap();
            let groups = r.multifault.as_ref().map_or(0, |m| m.groups_processed);
            eprintln!(
                "n {n} t {t}: {:?}, {} excluded, {groups} groups",
                r.decision,
                r.exclusions.len()
            );
            group.bench_with_input(
                BenchmarkId::new(format!("reconstruction_t{t}"), n),
                &epoch,
                |b, e| b.iter(|| raim.process(black_box(&rec), black_box(e)).unwrap()),
            );
            group.bench_with_input(
                BenchmarkId::new(format!("sequential_t{t}"), n),
                &epoch,
                |b, e| b.iter(|| raim.process(black_box(&seq), black_box(e)).unwrap()),
            );
        }
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).warm_up_time(std::time::Duration::from_millis(300)).measurement_time(std::time::Duration::from_secs(2));
    targets = bench
}
criterion_main!(benches);
