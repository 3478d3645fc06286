//! Per-epoch cost of the particle-filter RAIM (raim_core::pf, SPEC §10):
//! the whole FDI epoch (main + one auxiliary filter per satellite) for the
//! EKF, the SIR PF and the GA-PF, with 100 and 300 particles, 6 and 12
//! satellites, f32 state (the device precision) and f64.
//! Run: cargo bench -p raim-core --bench pf

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use raim_core::pf::{Ekf, Estimator, GaPf, PfConfig, PfRaim, SirPf};
use raim_core::{RangeObservation, Real, SatId, System};
use std::hint::black_box;

const RX: [f64; 3] = [3_512_000.0, 778_000.0, 5_248_000.0];

/// n GPS satellites at 26 560 km radius spread over the sky, with seeded
/// N(0, 3 m) noise (xorshift + Box-Muller) at epoch k.
fn epoch(n: usize, k: usize, state: &mut u64) -> Vec<RangeObservation> {
    let mut u = || {
        *state ^= *state << 13;
        *state ^= *state >> 7;
        *state ^= *state << 17;
        ((*state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    };
    let norm = (RX[0] * RX[0] + RX[1] * RX[1] + RX[2] * RX[2]).sqrt();
    let up = RX.map(|v| v / norm);
    let e = {
        let m = (up[0] * up[0] + up[1] * up[1]).sqrt();
        [-up[1] / m, up[0] / m, 0.0]
    };
    let nn = [
        up[1] * e[2] - up[2] * e[1],
        up[2] * e[0] - up[0] * e[2],
        up[0] * e[1] - up[1] * e[0],
    ];
    (0..n)
        .map(|i| {
            let az = i as f64 * 2.4;
            let el = 0.3 + 1.1 * ((i * 7) % 12) as f64 / 12.0;
            let l: [f64; 3] = core::array::from_fn(|j| {
                el.cos() * az.sin() * e[j] + el.cos() * az.cos() * nn[j] + el.sin() * up[j]
            });
            let b = 2.0 * (l[0] * RX[0] + l[1] * RX[1] + l[2] * RX[2]);
            let c = norm * norm - 26_560_000.0f64.powi(2);
            let d = (-b + (b * b - 4.0 * c).sqrt()) / 2.0;
            let s: [f64; 3] = core::array::from_fn(|j| RX[j] + d * l[j]);
            let g = (-2.0 * u().ln()).sqrt() * (2.0 * std::f64::consts::PI * u()).cos();
            RangeObservation {
                id: SatId::new(System::Gps, i as u8 + 1),
                pseudorange_m: d + 100.0 + 0.5 * k as f64 + 3.0 * g,
                position_m: s,
                sigma_m: Some(3.0),
            }
        })
        .collect()
}

fn bench_one<T: Real, E: Estimator<T>>(c: &mut Criterion, name: &str, n: usize) {
    let cfg = PfConfig {
        sigma_m: 3.0,
        ..PfConfig::default()
    };
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let epochs: Vec<_> = (0..64).map(|k| epoch(n, k, &mut state)).collect();
    let mut m: Box<PfRaim<T, E, 12>> = Box::new(PfRaim::new(1));
    let mut t = 0.0;
    for e in epochs.iter().take(5) {
        m.process(&cfg, t, e).unwrap();
        t += 1.0;
    }
    let mut k = 0;
    c.bench_with_input(BenchmarkId::new(name, n), &n, |b, _| {
        b.iter(|| {
            let e = &epochs[k % epochs.len()];
            k += 1;
            t += 1.0;
            black_box(m.process(&cfg, t, black_box(e)).unwrap())
        })
    });
}

fn pf(c: &mut Criterion) {
    for n in [6, 12] {
        bench_one::<f32, Ekf<f32>>(c, "ekf_f32", n);
        bench_one::<f32, SirPf<f32, 100>>(c, "pf100_f32", n);
        bench_one::<f32, SirPf<f32, 300>>(c, "pf300_f32", n);
        bench_one::<f32, GaPf<f32, 100>>(c, "gapf100_f32", n);
        bench_one::<f32, GaPf<f32, 300>>(c, "gapf300_f32", n);
        bench_one::<f64, GaPf<f64, 300>>(c, "gapf300_f64", n);
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).warm_up_time(std::time::Duration::from_millis(500)).measurement_time(std::time::Duration::from_secs(2));
    targets = pf
}
criterion_main!(benches);
