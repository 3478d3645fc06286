//! The per-epoch cost the MCUSUM adds (SPEC §7): `Raim::process` with the
//! MCUSUM off and on (transport, the default), at n = 8, 12, 20, 32 clean
//! satellites on a slowly turning sky (the parity basis changes every epoch,
//! as in flight), and the bare `Mcusum::update` (transport + Crosier step).
//! Run: cargo bench -p raim-core --bench mcusum

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use raim_core::config::Carry;
use raim_core::sequential::mcusum::Mcusum;
use raim_core::solve::solve;
use raim_core::{Config, Epoch, LinearObservation, Raim, SatId, System};
use std::hint::black_box;

/// Epochs prepared ahead and cycled through (the noise repeats after this many).
const EPOCHS: usize = 256;

/// n satellites on a golden-angle spiral, turned by `turn_deg`, unit sigma,
/// N(0, 1) noise from a seeded xorshift + Box-Muller (white, so the MCUSUM
/// stays in control as on a fault-free flight).
fn sky(n: usize, turn_deg: f64, state: &mut u64) -> Vec<LinearObservation> {
    let mut uniform = || {
        *state ^= *state << 13;
        *state ^= *state >> 7;
        *state ^= *state << 17;
        ((*state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    };
    (0..n)
        .map(|i| {
            let az = (i as f64 * 137.507_764_f64 + turn_deg).rem_euclid(360.0);
            let el = 10.0 + 75.0 * ((i * 7) % n) as f64 / n as f64;
            let noise = (-2.0 * uniform().ln()).sqrt() * (std::f64::consts::TAU * uniform()).cos();
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
                noise,
            );
            o.sigma_m = Some(1.0);
            o
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let off = Config::default();
    let on = Config::default().split_false_alarm_budget(0.5);
    let mut group = c.benchmark_group("mcusum_epoch");
    for n in [8usize, 12, 20, 32] {
        // The sky turns 0.01 deg per epoch, so every epoch has a new basis.
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let skies: Vec<Vec<LinearObservation>> = (0..EPOCHS)
            .map(|t| sky(n, 0.01 * t as f64, &mut state))
            .collect();
        for (label, cfg) in [("off", off), ("on", on)] {
            let mut raim = Raim::<32>::new();
            let _ = raim.process(&cfg, &Epoch::linear(0.0, &skies[0]));
            let mut t = 0usize;
            group.bench_with_input(BenchmarkId::new(label, n), &skies, |b, skies| {
                b.iter(|| {
                    t += 1;
                    raim.process(
                        black_box(&cfg),
                        black_box(&Epoch::linear(t as f64, &skies[t % 2])),
                    )
                })
            });
        }
        // The MCUSUM update alone on prepared solutions.
        let mut mask = [false; 32];
        mask.iter_mut().take(n).for_each(|m| *m = true);
        let sols: Vec<_> = skies
            .iter()
            .map(|s| solve::<32>(&off, &Epoch::linear(0.0, s), &mask).expect("solvable"))
            .collect();
        let mut mc = Mcusum::<32>::new();
        let mut t = 0usize;
        group.bench_with_input(BenchmarkId::new("update_only", n), &sols, |b, sols| {
            b.iter(|| {
                t += 1;
                let s = &sols[t % EPOCHS];
                mc.update(
                    black_box(&s.ids[..s.rows()]),
                    black_box(&s.parity),
                    1.0,
                    Carry::Transport,
                    20.0,
                )
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
