//! Test-only helpers: deterministic geometries and noise (no `rand` needed).
#![allow(dead_code)]

extern crate std;
use std::vec::Vec;

use crate::measurement::{LinearObservation, RangeObservation, SatId, System};

/// A test's tolerance in the test build's default precision
/// ([`crate::Stat`]): `f64_tol` when `Stat` is f64 (the f64 tolerances are
/// the ones the tests always had and never change), `f32_tol` with the
/// `test-f32` feature (the device's precision, `cargo test -p raim-core
/// --release --features test-f32 --lib`). Each caller names the constant
/// and says why the f32 value is what it is.
pub const fn at_stat(f64_tol: f64, f32_tol: f64) -> f64 {
    if cfg!(feature = "test-f32") {
        f32_tol
    } else {
        f64_tol
    }
}

/// The stack of a test thread that builds large engines by value. In the
/// debug profile a constructor passes its value through a chain of frames,
/// each `new`/`Default` holding its fields' temporaries: about three times
/// the engine's size (measured on the debug test binary with `objdump -d`,
/// the frames' `sub $n, %rsp`), so a test that builds a few of them
/// overflows the 2 MiB default test thread. A constructor that builds in
/// place (a `const fn new` into a static) would need none of it.
pub const BIG_STACK_BYTES: usize = 32 << 20;

/// Runs `f` on a thread of [`BIG_STACK_BYTES`], passing its panic on.
pub fn on_big_stack<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    std::thread::scope(|s| {
        std::thread::Builder::new()
            .stack_size(BIG_STACK_BYTES)
            .spawn_scoped(s, f)
            .expect("spawning a test thread")
            .join()
            .unwrap_or_else(|e| std::panic::resume_unwind(e))
    })
}

/// xorshift64* with Box-Muller normals: deterministic, seedable.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    pub fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let v = self.0.wrapping_mul(0x2545_F491_4F6C_DD1D);
        ((v >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    pub fn normal(&mut self) -> f64 {
        let (u1, u2) = (self.uniform(), self.uniform());
        (-2.0 * u1.ln()).sqrt() * (2.0 * core::f64::consts::PI * u2).cos()
    }
}

/// Eight GPS satellites spread in azimuth and elevation (degrees).
pub const SKY8: [(f64, f64); 8] = [
    (0.0, 85.0),
    (45.0, 30.0),
    (100.0, 50.0),
    (150.0, 20.0),
    (200.0, 60.0),
    (250.0, 25.0),
    (300.0, 40.0),
    (340.0, 15.0),
];

/// Linear observations for az/el pairs (degrees), GPS PRNs 1.., unit sigma,
/// noise from `rng` (times `sigma_m`) and the given faults (row, metres).
pub fn linear_epoch(
    sky: &[(f64, f64)],
    sigma_m: f64,
    rng: &mut Rng,
    faults: &[(usize, f64)],
) -> Vec<LinearObservation> {
    sky.iter()
        .enumerate()
        .map(|(i, &(az, el))| {
            let fault: f64 = faults.iter().filter(|f| f.0 == i).map(|f| f.1).sum();
            let mut o = LinearObservation::from_az_el(
                SatId::new(System::Gps, i as u8 + 1),
                az.to_radians(),
                el.to_radians(),
                sigma_m * rng.normal() + fault,
            );
            o.sigma_m = Some(sigma_m);
            o
        })
        .collect()
}

/// A receiver on the ground (ECEF, m) for the pseudorange tests.
pub const RX_ECEF_M: [f64; 3] = [-3_962_108.673, 3_381_309.574, 3_668_678.638];

/// Receiver clocks by system index (GPS, Galileo; m) for [`range_epoch`].
pub const CLOCKS_GE_M: [f64; 5] = [1234.5, -987.0, 0.0, 0.0, 0.0];

/// Five GPS and three Galileo satellites (system, PRN, az, el in degrees).
pub const SKY_GE8: [(System, u8, f64, f64); 8] = [
    (System::Gps, 1, 10.0, 80.0),
    (System::Gps, 5, 80.0, 30.0),
    (System::Gps, 9, 170.0, 45.0),
    (System::Gps, 12, 250.0, 20.0),
    (System::Gps, 17, 320.0, 55.0),
    (System::Galileo, 3, 40.0, 25.0),
    (System::Galileo, 8, 200.0, 65.0),
    (System::Galileo, 11, 290.0, 35.0),
];

/// Pseudorange observations for a receiver at `rx_ecef_m` with clock
/// `clock_m[system]`, satellites placed at GPS orbit radius along az/el.
pub fn range_epoch(
    rx_ecef_m: [f64; 3],
    sky: &[(System, u8, f64, f64)],
    clock_m: &[f64; 5],
    sigma_m: f64,
    rng: &mut Rng,
    faults: &[(usize, f64)],
) -> Vec<RangeObservation> {
    let g = crate::frames::ecef_to_geodetic(rx_ecef_m);
    let r = crate::frames::enu_rotation(&g);
    sky.iter()
        .enumerate()
        .map(|(i, &(sys, prn, az, el))| {
            let (az, el) = (az.to_radians(), el.to_radians());
            let enu = [el.cos() * az.sin(), el.cos() * az.cos(), el.sin()];
            let d = crate::frames::unrotate(&r, enu);
            // Range to a sphere of radius 26,560 km.
            let rs = 26_560_000.0f64;
            let b = rx_ecef_m
                .iter()
                .zip(d.iter())
                .map(|(p, q)| p * q)
                .sum::<f64>();
            let c = rx_ecef_m.iter().map(|p| p * p).sum::<f64>() - rs * rs;
            let range = -b + (b * b - c).sqrt();
            let pos = [
                rx_ecef_m[0] + range * d[0],
                rx_ecef_m[1] + range * d[1],
                rx_ecef_m[2] + range * d[2],
            ];
            let fault: f64 = faults.iter().filter(|f| f.0 == i).map(|f| f.1).sum();
            RangeObservation {
                id: SatId::new(sys, prn),
                pseudorange_m: range + clock_m[sys.index()] + sigma_m * rng.normal() + fault,
                position_m: pos,
                sigma_m: Some(sigma_m),
            }
        })
        .collect()
}
