//! One epoch repeated, for instruction counts under valgrind (BENCHMARKS.md): `cargo build --release -p raim-core --example epoch_cost`, then
//! `valgrind --tool=callgrind --callgrind-out-file=/dev/null
//! target/release/examples/epoch_cost FORM N FAULT_M REPS [warm]` with FORM
//! `linear` (the criterion bench's sky: golden-angle spiral, unit sigma) or
//! `ranges` (the same sky as pseudoranges from a receiver at the 0759
//! station, GPS + Galileo clocks, elevation sigma model, a-priori 100 m off).
//! The cost per epoch is (total(REPS) - total(0)) / REPS: the first epoch
//! (threshold cache, sky set-up) is run in both.

use raim_core::frames::{ecef_to_geodetic, enu_rotation, unrotate};
use raim_core::{Config, Epoch, LinearObservation, Raim, RangeObservation, SatId, System};
use std::hint::black_box;

const RX: [f64; 3] = [-3_962_108.673, 3_381_309.574, 3_668_678.638];

fn az_el(i: usize, n: usize) -> (f64, f64) {
    let az = (i as f64 * 137.507_764_f64).rem_euclid(360.0);
    let el = 10.0 + 75.0 * ((i * 7) % n) as f64 / n as f64;
    (az.to_radians(), el.to_radians())
}

fn noise(i: usize) -> f64 {
    ((i as f64 * 12.9898).sin() * 43758.5453).fract() - 0.5
}

fn id(i: usize) -> SatId {
    let sys = if i.is_multiple_of(2) {
        System::Gps
    } else {
        System::Galileo
    };
    SatId::new(sys, i as u8 + 1)
}

fn linear(n: usize, fault_m: f64) -> Vec<LinearObservation> {
    (0..n)
        .map(|i| {
            let (az, el) = az_el(i, n);
            let r = noise(i) + if i == 2 { fault_m } else { 0.0 };
            let mut o = LinearObservation::from_az_el(id(i), az, el, r);
            o.sigma_m = Some(1.0);
            o
        })
        .collect()
}

fn ranges(n: usize, fault_m: f64) -> Vec<RangeObservation> {
    let rot = enu_rotation(&ecef_to_geodetic(RX));
    (0..n)
        .map(|i| {
            let (az, el) = az_el(i, n);
            let d = unrotate(&rot, [el.cos() * az.sin(), el.cos() * az.cos(), el.sin()]);
            let rs = 26_560_000.0f64;
            let b: f64 = RX.iter().zip(d.iter()).map(|(p, q)| p * q).sum();
            let c = RX.iter().map(|p| p * p).sum::<f64>() - rs * rs;
            let range = -b + (b * b - c).sqrt();
            let clock = if i.is_multiple_of(2) { 1234.5 } else { -987.0 };
            RangeObservation {
                id: id(i),
                pseudorange_m: range + clock + noise(i) + if i == 2 { fault_m } else { 0.0 },
                position_m: [0, 1, 2].map(|k| RX[k] + range * d[k]),
                sigma_m: None,
            }
        })
        .collect()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let form = args.get(1).map(String::as_str).unwrap_or("linear");
    let n: usize = args.get(2).and_then(|v| v.parse().ok()).unwrap_or(20);
    let fault_m: f64 = args.get(3).and_then(|v| v.parse().ok()).unwrap_or(0.0);
    let reps: usize = args.get(4).and_then(|v| v.parse().ok()).unwrap_or(1000);
    let warm = args.get(5).is_some_and(|v| v == "warm");
    let cfg = Config::default();
    let mut raim = Raim::<32>::new();
    raim.set_warm_start(warm);
    let lin = linear(n, fault_m);
    let rng = ranges(n, fault_m);
    let apriori = Some(RX.map(|v| v + 100.0 / 3f64.sqrt()));
    let epoch = if form == "ranges" {
        Epoch::ranges(0.0, &rng, apriori)
    } else {
        Epoch::linear(0.0, &lin)
    };
    let first = raim.process(&cfg, &epoch).expect("epoch");
    for _ in 0..reps {
        let _ = black_box(raim.process(black_box(&cfg), black_box(&epoch)));
    }
    eprintln!(
        "{form} n={n} fault={fault_m} m: {:?}, {} exclusions, {} iterations",
        first.decision,
        first.exclusions.len(),
        first.iterations
    );
}
