//! "Do the work once": the reused linearisation, the sibling
//! start of FDE subsets and the warm start, each against an independent
//! reference (a model built from scratch at the solution, or a cold solve).
extern crate std;
use super::*;
use crate::frames::{ecef_to_geodetic, elevation_rad};
use crate::monitor::Raim;
use crate::testutil::{range_epoch, Rng, CLOCKS_GE_M as CLOCK, RX_ECEF_M as RX};
use nalgebra::{DMatrix, DVector};
use std::vec::Vec;

fn sky12() -> Vec<(System, u8, f64, f64)> {
    (0..12)
        .map(|i| {
            let sys = if i % 3 == 2 {
                System::Galileo
            } else {
                System::Gps
            };
            (
                sys,
                i as u8 + 1,
                (i as f64 * 137.5) % 360.0,
                7.0 + (i as f64 * 29.0) % 80.0,
            )
        })
        .collect()
}

/// Observations without a sigma, so the elevation model is used.
fn modelled(rx: [f64; 3], seed: u64, faults: &[(usize, f64)]) -> Vec<RangeObservation> {
    range_epoch(rx, &sky12(), &CLOCK, 0.8, &mut Rng::new(seed), faults)
        .into_iter()
        .map(|o| RangeObservation { sigma_m: None, ..o })
        .collect()
}

/// Independent reference at a given position: geodetic, rotation,
/// elevations and sigmas evaluated there from scratch, and the weighted
/// SSE of the linearised model by dense normal equations (nalgebra).
fn reference_at(
    cfg: &Config,
    sats: &[RangeObservation],
    x: [f64; 3],
    clock: &[f64],
) -> (Vec<f64>, Vec<f64>, f64) {
    let rot = enu_rotation(&ecef_to_geodetic(x));
    let (mut els, mut sigmas) = (Vec::new(), Vec::new());
    let n = sats.len();
    let mut h = DMatrix::zeros(n, 5);
    let mut z = DVector::zeros(n);
    for (i, s) in sats.iter().enumerate() {
        let d = [
            s.position_m[0] - x[0],
            s.position_m[1] - x[1],
            s.position_m[2] - x[2],
        ];
        let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let u = rotate(&rot, [d[0] / r, d[1] / r, d[2] / r]);
        let el = elevation_rad(u);
        let sigma = cfg.sigma_model.sigma_m(el);
        els.push(el);
        sigmas.push(sigma);
        let c = s.id.system.index();
        for k in 0..3 {
            h[(i, k)] = -u[k] / sigma;
        }
        h[(i, 3 + c)] = 1.0 / sigma;
        z[i] = (s.pseudorange_m - r - clock[c]) / sigma;
    }
    let hth = h.transpose() * &h;
    let dx = hth.try_inverse().unwrap() * h.transpose() * &z;
    let res = &z - &h * dx;
    (els, sigmas, res.dot(&res))
}

/// Cold from the Earth's centre: the per-satellite model the solution
/// carries (computed at a linearisation point within RELINEARISE_M) agrees
/// with one computed from scratch at the solution, within the stated
/// bounds; so does the statistic; and the noise-free position is exact.
#[test]
fn reused_linearisation_matches_a_model_built_at_the_solution() {
    const EL_TOL_RAD: f64 = RELINEARISE_EL_RAD;
    const SIGMA_REL_TOL: f64 = 3e-4;
    // The SSE moves with the weights: twice the sigma bound, relative.
    const SSE_REL_TOL: f64 = 6e-4;
    const POSITION_TOL_M: f64 = 1e-6;
    let cfg = Config::default();
    let sats = modelled(RX, 5, &[(4, 20.0)]);
    let mask = [true; 16];
    let mut mask12 = mask;
    mask12.iter_mut().skip(12).for_each(|m| *m = false);
    let sol = solve::<16>(&cfg, &Epoch::ranges(0.0, &sats, None), &mask12).unwrap();
    let x = sol.position_ecef_m.unwrap();
    let lin = sol.linearisation.unwrap();
    assert!(lin.distance_m(&x) <= RELINEARISE_M);
    let clock = [sol.clock_m[0].unwrap(), sol.clock_m[1].unwrap()];
    let (els, sigmas, sse) = reference_at(&cfg, &sats, x, &clock);
    for k in 0..12 {
        assert!((sol.elevation_rad[k] - els[k]).abs() <= EL_TOL_RAD, "{k}");
        assert!(
            ((sol.sigma_m[k] - sigmas[k]) / sigmas[k]).abs() <= SIGMA_REL_TOL,
            "{k}"
        );
    }
    assert!(
        ((sol.parity.sse().to_f64() - sse) / sse).abs() < SSE_REL_TOL,
        "{} vs {sse}",
        sol.parity.sse()
    );
    // Noise-free: the position itself.
    let exact: Vec<RangeObservation> =
        range_epoch(RX, &sky12(), &CLOCK, 0.0, &mut Rng::new(5), &[])
            .into_iter()
            .map(|o| RangeObservation { sigma_m: None, ..o })
            .collect();
    let sol = solve::<16>(&cfg, &Epoch::ranges(0.0, &exact, None), &mask12).unwrap();
    let p = sol.position_ecef_m.unwrap();
    for k in 0..3 {
        assert!((p[k] - RX[k]).abs() < POSITION_TOL_M, "{p:?}");
    }
}

/// An FDE subset started from the all-in-view solution of the same epoch
/// (reusing its model) agrees with the cold solve of the same subset, in
/// fewer iterations.
#[test]
fn sibling_start_agrees_with_a_cold_subset_solve() {
    const POSITION_TOL_M: f64 = 1e-3;
    const SSE_REL_TOL: f64 = 1e-6;
    let cfg = Config::default();
    let sats = modelled(RX, 9, &[(4, 40.0)]);
    let epoch = Epoch::ranges(0.0, &sats, Some(RX.map(|v| v + 3000.0)));
    let mut all = [false; 16];
    all.iter_mut().take(12).for_each(|m| *m = true);
    let full = solve::<16>(&cfg, &epoch, &all).unwrap();
    let mut subset = all;
    subset[4] = false;
    let cold = solve::<16>(&cfg, &epoch, &subset).unwrap();
    let mut warm = Solution::<16>::empty();
    solve_from(&cfg, &epoch, &subset, Start::Sibling(&full), &mut warm).unwrap();
    let (a, b) = (cold.position_ecef_m.unwrap(), warm.position_ecef_m.unwrap());
    for k in 0..3 {
        assert!((a[k] - b[k]).abs() < POSITION_TOL_M, "{a:?} {b:?}");
    }
    let (cold_sse, warm_sse) = (cold.parity.sse().to_f64(), warm.parity.sse().to_f64());
    assert!(
        ((cold_sse - warm_sse) / cold_sse).abs() < SSE_REL_TOL,
        "{cold_sse} vs {warm_sse}"
    );
    assert_eq!(cold.ids, warm.ids);
    assert!(
        warm.iterations < cold.iterations,
        "{} vs {}",
        warm.iterations,
        cold.iterations
    );
    // Linearised input: the sibling's elevations and sigmas are exact.
    let lin = crate::testutil::linear_epoch(&crate::testutil::SKY8, 1.0, &mut Rng::new(2), &[]);
    let lin: Vec<_> = lin
        .into_iter()
        .map(|o| LinearObservation { sigma_m: None, ..o })
        .collect();
    let e = Epoch::linear(0.0, &lin);
    let mut m8 = [false; 16];
    m8.iter_mut().take(8).for_each(|m| *m = true);
    let full = solve::<16>(&cfg, &e, &m8).unwrap();
    m8[3] = false;
    let cold = solve::<16>(&cfg, &e, &m8).unwrap();
    let mut warm = Solution::<16>::empty();
    solve_from(&cfg, &e, &m8, Start::Sibling(&full), &mut warm).unwrap();
    assert_eq!(cold.sigma_m, warm.sigma_m);
    assert_eq!(cold.parity.sse().to_bits(), warm.parity.sse().to_bits());
}

/// The warm start from the last epoch's fix: a receiver moving 5 m per
/// 1 s epoch, noise and a fault every 5th epoch; every decision, exclusion
/// and identification equals the cold engine's, positions agree within
/// 1e-3 m, and the statistic and PLs within the relinearisation bounds (the
/// warm engine's model may be evaluated at the last epoch's point, up to
/// RELINEARISE_M away: sigmas within 3e-4, so D^2 within 6e-4 and the PLs
/// within 3e-4 + 2e-5 relative), in fewer iterations. A fix
/// older than WARM_START_MAX_AGE_S is not used (bit-exact with a cold run).
///
/// Verifies: SPEC-1
#[test]
fn warm_start_agrees_with_cold_start() {
    const POSITION_TOL_M: f64 = 1e-3;
    const STAT_REL_TOL: f64 = 6e-4;
    const PL_REL_TOL: f64 = 3.2e-4;
    let cfg = Config::default();
    let (mut worst_stat, mut worst_pl) = (0.0f64, 0.0f64);
    let mut cold = Raim::<16>::new();
    let mut warm = Raim::<16>::new();
    warm.set_warm_start(true);
    let (mut it_cold, mut it_warm) = (0, 0);
    let enu = enu_rotation(&ecef_to_geodetic(RX));
    let east = unrotate(&enu, [1.0, 0.0, 0.0]);
    for t in 0..30 {
        let rx = [0, 1, 2].map(|k| RX[k] + 5.0 * t as f64 * east[k]);
        let faults: Vec<(usize, f64)> = if t % 5 == 4 {
            std::vec![(t % 12, 60.0)]
        } else {
            std::vec![]
        };
        let sats = modelled(rx, 100 + t as u64, &faults);
        let epoch = Epoch::ranges(t as f64, &sats, Some(RX.map(|v| v + 200.0)));
        let a = cold.process(&cfg, &epoch).unwrap();
        let b = warm.process(&cfg, &epoch).unwrap();
        assert_eq!(a.decision, b.decision, "t={t}");
        assert_eq!(a.identified, b.identified, "t={t}");
        let ids = |r: &crate::result::EpochResult<16>| {
            r.exclusions.iter().map(|e| e.id).collect::<Vec<_>>()
        };
        assert_eq!(ids(&a), ids(&b), "t={t}");
        let (pa, pb) = (a.position_ecef_m.unwrap(), b.position_ecef_m.unwrap());
        for k in 0..3 {
            assert!((pa[k] - pb[k]).abs() < POSITION_TOL_M, "t={t}");
        }
        let rel = |x: f64, y: f64| ((x - y) / x).abs();
        worst_stat = worst_stat.max(rel(a.test.statistic, b.test.statistic));
        worst_pl = worst_pl.max(rel(a.protection.hpl_m, b.protection.hpl_m));
        worst_pl = worst_pl.max(rel(a.protection.vpl_m, b.protection.vpl_m));
        it_cold += a.iterations;
        it_warm += b.iterations;
    }
    std::println!("warm vs cold: D^2 {worst_stat:.2e}, PL {worst_pl:.2e} relative; iterations {it_warm} vs {it_cold}");
    assert!(worst_stat < STAT_REL_TOL, "{worst_stat}");
    assert!(worst_pl < PL_REL_TOL, "{worst_pl}");
    // In f64, fewer iterations (62 vs 86). In f32 both take the minimum,
    // 2 per epoch (60 vs 60): the convergence step's floor
    // (STEP_ROUNDING_SCALE_M x eps, 1.2e-2 m) ends the cold start as early,
    // so the warm start saves nothing there; it must never cost more.
    if cfg!(feature = "test-f32") {
        assert!(it_warm <= it_cold, "{it_warm} vs {it_cold}");
    } else {
        assert!(it_warm < it_cold, "{it_warm} vs {it_cold}");
    }
    // A stale fix (61 s later) is ignored: bit-exact with a fresh engine.
    let sats = modelled(RX, 7, &[]);
    let epoch = Epoch::ranges(29.0 + WARM_AGE_PLUS, &sats, Some(RX));
    let a = Raim::<16>::new().process(&cfg, &epoch).unwrap();
    let b = warm.process(&cfg, &epoch).unwrap();
    assert_eq!(a.test.statistic.to_bits(), b.test.statistic.to_bits());
    assert_eq!(a.position_ecef_m, b.position_ecef_m);
}

const WARM_AGE_PLUS: f64 = crate::snapshot::WARM_START_MAX_AGE_S + 1.0;

/// The linearisation's geodetic point (Bowring start, then the fixed-point
/// iteration) and the first-order update for the reported position both
/// agree with the plain 10-iteration conversion: latitude and longitude
/// within 1e-11 rad (0.06 mm), height within 1e-4 m, over the globe
/// (latitudes -85..85 deg, heights -100 m..10 km) and offsets up to 1 m.
#[test]
fn geodetic_shortcuts_agree_with_the_iterative_conversion() {
    use crate::frames::geodetic_to_ecef;
    const ANGLE_TOL_RAD: f64 = 1e-11;
    const HEIGHT_TOL_M: f64 = 1e-4;
    let mut rng = crate::testutil::Rng::new(7);
    for _ in 0..2000 {
        let g = Geodetic {
            lat_rad: (rng.uniform() * 170.0 - 85.0).to_radians(),
            lon_rad: (rng.uniform() * 360.0 - 180.0).to_radians(),
            height_m: rng.uniform() * 10_100.0 - 100.0,
        };
        let p = geodetic_to_ecef(g);
        let l = Linearisation::at(p, None);
        let exact = ecef_to_geodetic(p);
        assert!((l.geodetic.lat_rad - exact.lat_rad).abs() < ANGLE_TOL_RAD);
        assert!((l.geodetic.lon_rad - exact.lon_rad).abs() < ANGLE_TOL_RAD);
        assert!((l.geodetic.height_m - exact.height_m).abs() < HEIGHT_TOL_M);
        let off = [
            rng.uniform() - 0.5,
            rng.uniform() - 0.5,
            rng.uniform() - 0.5,
        ];
        let x = [p[0] + off[0], p[1] + off[1], p[2] + off[2]];
        let near = l.geodetic_of(x);
        let exact = ecef_to_geodetic(x);
        assert!((near.lat_rad - exact.lat_rad).abs() < ANGLE_TOL_RAD);
        assert!((near.lon_rad - exact.lon_rad).abs() < ANGLE_TOL_RAD);
        assert!((near.height_m - exact.height_m).abs() < HEIGHT_TOL_M);
    }
}

/// The linearised model built in passes (the f64 engine's `solve_linear`)
/// and one satellite at a time (`solve_linear_by_row`, the f32 engine's)
/// give the same solution bit for bit: random skies of 5-32 satellites in
/// 1-3 systems, given and modelled sigmas, all-in-view and random subsets
/// started from the all-in-view sibling; and the same typed error, naming
/// the same first satellite, for bad sigmas.
#[test]
fn linear_passes_equal_the_row_builder() {
    const N: usize = 32;
    let cfg = Config::default();
    let mut rng = Rng::new(23);
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let same = |a: &Solution<N, f64>, b: &Solution<N, f64>| {
        let (p, q) = (&a.parity, &b.parity);
        assert_eq!(p.rows(), q.rows());
        assert_eq!(bits(p.s_ii()), bits(q.s_ii()));
        assert_eq!(bits(p.residuals()), bits(q.residuals()));
        assert_eq!(bits(p.p()), bits(q.p()));
        assert_eq!(bits(p.dx()), bits(q.dx()));
        for axis in 0..3 {
            assert_eq!(bits(p.gains()[axis]), bits(q.gains()[axis]));
        }
        assert_eq!(a.source, b.source);
        assert_eq!(a.ids, b.ids);
        assert_eq!(bits(&a.sigma_m), bits(&b.sigma_m));
        assert_eq!(bits(&a.elevation_rad), bits(&b.elevation_rad));
        assert_eq!(a.clocks, b.clocks);
        assert_eq!(a.clock_m, b.clock_m);
        assert_eq!(bits(&a.correction_enu_m), bits(&b.correction_enu_m));
    };
    for trial in 0..400 {
        let n = 5 + trial % 28;
        let systems = 1 + trial % 3;
        let sats: Vec<LinearObservation> = (0..n)
            .map(|i| {
                let sys = [System::Gps, System::Galileo, System::Beidou][i % systems];
                let az = rng.uniform() * core::f64::consts::TAU;
                let el = (5.0 + rng.uniform() * 85.0f64).to_radians();
                let mut o = LinearObservation::from_az_el(
                    SatId::new(sys, i as u8 + 1),
                    az,
                    el,
                    rng.uniform() * 10.0 - 5.0,
                );
                if rng.uniform() < 0.5 {
                    o.sigma_m = Some(0.3 + rng.uniform() * 3.0);
                }
                o
            })
            .collect();
        let mut mask = [false; N];
        mask[..n].iter_mut().for_each(|m| *m = true);
        let (mut a, mut b) = (Solution::<N, f64>::empty(), Solution::<N, f64>::empty());
        let ra = solve_linear(&cfg, &sats, &mask, None, &mut a);
        let rb = solve_linear_by_row(&cfg, &sats, &mask, None, &mut b);
        assert_eq!(ra, rb, "trial {trial}");
        if ra.is_err() {
            continue;
        }
        same(&a, &b);
        // A subset from the all-in-view sibling.
        let mut sub = mask;
        for m in sub[..n].iter_mut() {
            *m = rng.uniform() < 0.8;
        }
        let (mut c, mut d) = (Solution::<N, f64>::empty(), Solution::<N, f64>::empty());
        let rc = solve_linear(&cfg, &sats, &sub, Some(&a), &mut c);
        let rd = solve_linear_by_row(&cfg, &sats, &sub, Some(&a), &mut d);
        assert_eq!(rc, rd, "trial {trial} subset");
        if rc.is_ok() {
            same(&c, &d);
        }
        // Bad sigmas: the same error, the same first satellite named.
        let mut bad = sats.clone();
        let k = trial % n;
        bad[k].sigma_m = Some([-1.0, 0.0, f64::NAN, f64::INFINITY][trial % 4]);
        bad[n - 1].sigma_m = Some(-2.0);
        let (mut e, mut f) = (Solution::<N, f64>::empty(), Solution::<N, f64>::empty());
        let re = solve_linear(&cfg, &bad, &mask, None, &mut e);
        let rf = solve_linear_by_row(&cfg, &bad, &mask, None, &mut f);
        assert!(re.is_err());
        assert_eq!(
            std::format!("{re:?}"),
            std::format!("{rf:?}"),
            "trial {trial} bad"
        );
    }
}

/// The first-order geodetic update falls back to the iterative conversion
/// where it does not hold: within 1e-6 of cos(latitude) = 0 (the pole,
/// where dE / cos(lat) blows up) and where the longitude leaves (-pi, pi]
/// (a step east across the antimeridian). Both agree with the plain
/// conversion as the interior does (1e-11 rad, 1e-4 m); across the
/// antimeridian the longitude comes back wrapped to near -pi.
#[test]
fn geodetic_update_at_the_pole_and_the_antimeridian() {
    use crate::frames::geodetic_to_ecef;
    const ANGLE_TOL_RAD: f64 = 1e-11;
    const HEIGHT_TOL_M: f64 = 1e-4;
    let pi = core::f64::consts::PI;
    let cases = [
        // cos(lat) = 1.7e-9 < 1e-6: near the north pole.
        (pi / 2.0 - 1.7e-9, 0.3, [0.2, -0.1, 0.3]),
        // 1e-8 rad (6 cm) west of the antimeridian, then 0.9 m east.
        (0.4, pi - 1e-8, [0.0; 3]),
    ];
    for (i, (lat_rad, lon_rad, off)) in cases.into_iter().enumerate() {
        let p = geodetic_to_ecef(Geodetic {
            lat_rad,
            lon_rad,
            height_m: 120.0,
        });
        let l = Linearisation::at(p, None);
        let east = unrotate(&l.rotation, [0.9, 0.0, 0.0]);
        let step = if i == 1 { east } else { off };
        let x = [p[0] + step[0], p[1] + step[1], p[2] + step[2]];
        let near = l.geodetic_of(x);
        let exact = ecef_to_geodetic(x);
        assert!((near.lat_rad - exact.lat_rad).abs() < ANGLE_TOL_RAD, "{i}");
        assert!((near.lon_rad - exact.lon_rad).abs() < ANGLE_TOL_RAD, "{i}");
        assert!((near.height_m - exact.height_m).abs() < HEIGHT_TOL_M, "{i}");
        if i == 1 {
            assert!(near.lon_rad < -pi + 1e-6, "{near:?}");
        }
    }
}

/// `Solution::row_of` and the sibling cursor: with satellite 4 of 12
/// left out, epoch index i sits at row i below 4 and row i - 1 above, and
/// 4, 12 and beyond have no row. The cursor, asked in decreasing order
/// (against the order it expects), still returns each row's elevation and
/// sigma, found by a full search.
#[test]
fn rows_of_epoch_satellites_and_the_cursor_in_any_order() {
    let cfg = Config::default();
    let sats = modelled(RX, 3, &[]);
    let epoch = Epoch::ranges(0.0, &sats, Some(RX));
    let mut mask = [false; 16];
    mask.iter_mut().take(12).for_each(|m| *m = true);
    mask[4] = false;
    let s = solve::<16>(&cfg, &epoch, &mask).unwrap();
    assert_eq!(s.rows(), 11);
    for i in 0..12 {
        let want = match i {
            0..=3 => Some(i),
            4 => None,
            _ => Some(i - 1),
        };
        assert_eq!(s.row_of(i), want, "{i}");
    }
    assert_eq!((s.row_of(12), s.row_of(99)), (None, None));
    let mut cursor = SiblingModel::new(Some(&s));
    for i in (0..12).rev() {
        let got = cursor.get(i);
        match s.row_of(i) {
            Some(r) => assert_eq!(got, Some((s.elevation_rad[r], s.sigma_m[r])), "{i}"),
            None => assert_eq!(got, None, "{i}"),
        }
    }
    assert_eq!(SiblingModel::<16, Stat>::new(None).get(0), None);
}
