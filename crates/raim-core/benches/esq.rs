//! Seed 003's own claims (docs/ESQ.md): the cost of N* per epoch
//! (P_k of every mode at the PL, P_Sigma, P_max; the ARAIM solve itself is
//! not included: it is the ARAIM bench), and of one PCA epoch (window
//! covariance, SVD, test) for W = 60 and N = 12, 20, 32 satellites.
//! Run: cargo bench -p raim-core --bench esq

use criterion::{criterion_group, criterion_main, Criterion};
#[path = "common/araim_inputs.rs"]
mod araim_inputs;

use araim_inputs::{appendix_d, sky};
use raim_core::araim::esq::effective_samples;
use raim_core::araim::pca::{principal, Pca, PcaConfig};
use raim_core::araim::{Araim, AraimConfig, AraimSat, Ism, PlOutput};
use raim_core::System;
use std::hint::black_box;

fn n_star(c: &mut Criterion) {
    let cfg = AraimConfig::default();
    let ge = [System::Gps, System::Galileo];
    let mut engine = Box::new(Araim::<f64, 32, 1024>::new());
    for (name, sats, ism) in [
        ("appendix_d", appendix_d(), Ism::with(&ge, 1e-4)),
        ("sky20", sky(10, 1e-5), Ism::with(&ge, 1e-4)),
        ("sky30_pairs", sky(15, 1e-4), Ism::with(&ge, 1e-8)),
    ] {
        let out = engine.process(&cfg, &ism, &sats).unwrap().clone();
        let v = effective_samples(&out, 2, PlOutput::AddBracket).unwrap();
        eprintln!("{name}: {} modes, N* {:.4}", v.n_modes, v.n_star);
        c.bench_function(&format!("esq_n_star/{name}"), |b| {
            b.iter(|| effective_samples(black_box(&out), 2, PlOutput::AddBracket))
        });
    }
}

/// A deterministic residual stream: common clock + per-satellite wiggle.
fn residual(t: usize, i: usize) -> f64 {
    let x = (t * 31 + i * 17) as f64;
    5.0 * (t as f64 * 0.01).sin() + 0.3 * (x * 0.7).sin() + 0.2 * (x * 1.3).cos()
}

/// One PCA epoch on a warmed window (covariance + SVD + test) and the
/// SVD alone, for N slots and 2 * half satellites.
macro_rules! pca_epoch {
    ($c:expr, $n:literal, $half:expr) => {{
        let mut sats: Vec<AraimSat<f64>> = sky($half, 1e-5);
        let cfg = PcaConfig::default();
        let mut pca = Box::new(Pca::<f64, $n, 60>::new());
        for t in 0..61 {
            for (i, s) in sats.iter_mut().enumerate() {
                s.residual_m = residual(t, i);
            }
            pca.process(&cfg, t as f64, &sats).unwrap();
        }
        let mut t = 61usize;
        $c.bench_function(&format!("pca_epoch/w60_n{}", 2 * $half), |b| {
            b.iter(|| {
                t += 1;
                for (i, s) in sats.iter_mut().enumerate() {
                    s.residual_m = residual(t, i);
                }
                pca.process(&cfg, t as f64, black_box(&sats)).unwrap()
            })
        });
        let mut m = nalgebra::SMatrix::<f64, $n, $n>::zeros();
        for i in 0..$n {
            for j in 0..$n {
                m[(i, j)] = (0..60)
                    .map(|t| residual(t, i) * residual(t, j))
                    .sum::<f64>()
                    / 59.0;
            }
        }
        $c.bench_function(&format!("pca_svd/n{}", $n), |b| {
            b.iter(|| principal(black_box(m), 0.99))
        });
    }};
}

fn pca(c: &mut Criterion) {
    pca_epoch!(c, 12, 6);
    pca_epoch!(c, 20, 10);
    pca_epoch!(c, 32, 16);
}

criterion_group!(benches, n_star, pca);
criterion_main!(benches);
