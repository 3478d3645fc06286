//! ARAIM in the firmware under QEMU (mps2-an386): ISM frames and
//! ARAIM epochs are answered byte for byte as the host's `Server` answers
//! the same frames (the same `raim_proto`/`raim_core` code at the build's
//! `raim_core::Stat`; why bit-exactness holds across x86-64 and the M4F:
//! `qemu_vectors.rs`). Checked against independent numbers: the ADD v3.0
//! App. D publication (modes, VPL, HPL, EMT, sigma_v,acc) and, for the
//! 20-satellite sky, the injected fault.
//!
//! `cargo test --release -p host-tests --test qemu_araim`

#[path = "qemu_common/araim.rs"]
mod araim_common;
mod qemu_common;

use araim_common::{appendix_d, epoch_command, ranges_command, ranges_of, sky20, Scenario, Twin};
use raim_core::araim::{error_model, Araim, AraimConfig, AraimSat, FdeDecision, Ism};
use raim_core::frames::{ecef_to_geodetic, enu_rotation, rotate, unrotate};
use raim_core::RangeObservation;
use raim_core::{Decision, SatId, System};
use raim_proto::araim_msg::{AraimAnswer, AraimWireError, IsmSat, WireAraimResult, WireFde};
use raim_proto::message::{CommandRef, Response, ResponseBody};
use raim_proto::WireError;

/// What is wrong, the ISM entries and P_const.
type BadIsm = (&'static str, Vec<IsmSat>, [Option<f64>; 5]);

fn result(r: &Response) -> &WireAraimResult {
    match &r.body {
        ResponseBody::Araim(AraimAnswer::Result(w)) => w,
        other => panic!("{other:?}"),
    }
}

fn error(r: &Response) -> &WireError {
    match &r.body {
        ResponseBody::Error(e) => e,
        other => panic!("{other:?}"),
    }
}

/// App. D's vertical effective sample quantity, docs/ESQ.md (f64 core).
const N_STAR_APP_D: f64 = 1.334;
/// Its printed precision plus the f32 engine's spread (dimensionless).
const N_STAR_TOL: f64 = 0.005;

#[test]
fn qemu_araim_appendix_d_and_a_20_satellite_sky_match_the_host() {
    let mut t = Twin::new(qemu_common::session());
    // App. D: the published numbers, and the host's bytes.
    let (d, want) = appendix_d();
    let r = t.ask(d.ism_command(), "App. D ISM");
    assert_eq!(
        r.body,
        ResponseBody::Araim(AraimAnswer::IsmAccepted { satellites: 10 })
    );
    let r = t.ask(epoch_command(0.0, &d.obs), "App. D epoch");
    let w = result(&r);
    let num = |k: &str| want[k].as_f64().unwrap();
    let printed_m = want["tolerances"]["printed_m"].as_f64().unwrap();
    let a = &w.all_in_view;
    assert_eq!(u64::from(a.modes), want["modes"].as_u64().unwrap());
    assert!((a.vpl_m - num("vpl_m")).abs() <= printed_m, "{a:?}");
    assert!((a.hpl_m - num("hpl_m")).abs() <= printed_m + 0.01, "{a:?}");
    assert!((a.emt_m - num("emt_m")).abs() <= printed_m, "{a:?}");
    assert!(
        (a.sigma_v_acc_m - num("sigma_v_acc_m")).abs() <= printed_m,
        "{a:?}"
    );
    assert!((a.vpl_exact_m - num("vpl_root_m")).abs() <= 0.01, "{a:?}");
    assert_eq!((w.decision, w.fde), (Decision::Ok, WireFde::NoFault));
    // Seed 003's N* on the device: App. D's vertical N* from
    // the f64 core, docs/ESQ.md (P_Sigma checked there against the
    // allocated risk at the PL root), within the f32 engine's spread.
    let n_star = w.n_star_vertical.expect("N* on App. D");
    eprintln!("App. D N* (vertical) on the device: {n_star}");
    assert!((n_star - N_STAR_APP_D).abs() <= N_STAR_TOL, "{n_star}");

    // The 20-satellite sky: clean, then 100 m on each of the first three
    // satellites in turn (each FDE ~9.5 M guest instructions in f32).
    let clean = sky20(usize::MAX, 0.0);
    t.ask(clean.ism_command(), "sky20 ISM");
    let r = t.ask(epoch_command(1.0, &clean.obs), "sky20 clean");
    assert_eq!(result(&r).decision, Decision::Ok);
    assert_eq!(result(&r).all_in_view.modes, 22);
    let mut excluded = 0;
    for faulty in 0..3 {
        let s = sky20(faulty, 100.0);
        let r = t.ask(
            epoch_command(2.0 + faulty as f64, &s.obs),
            &format!("sky20 100 m on {faulty}"),
        );
        let w = result(&r);
        assert!(!w.all_in_view.detection_passed);
        if let WireFde::Excluded { .. } = w.fde {
            // Only the faulty satellite, never another one.
            assert_eq!(w.excluded.as_slice(), &[s.obs[faulty].id]);
            excluded += 1;
        } else {
            assert_eq!(w.decision, Decision::Alarm, "{w:?}");
        }
    }
    assert_eq!(excluded, 3, "{excluded} of 3 excluded");

    // 24 satellites need satellite pairs (327 modes): a 100 m fault on the
    // last satellite is still excluded on the device (FDE whenever the
    // modes fit; about 55 M guest instructions), bit for bit with the host.
    let s = araim_common::sky(24, 23, 100.0);
    t.ask(s.ism_command(), "sky24 ISM");
    let r = t.ask(epoch_command(10.0, &s.obs), "sky24 100 m on the last");
    let w = result(&r);
    assert_eq!(w.all_in_view.modes, 327);
    assert!(matches!(w.fde, WireFde::Excluded { .. }), "{:?}", w.fde);
    assert_eq!(w.excluded.as_slice(), &[s.obs[23].id]);

    // Two faults on that sky: no single event is consistent, and FDE's
    // stage 2 (the multi-event candidates, core `fde_multi` tests against
    // the brute force) excludes the pair, bit for bit with the host
    // (~115 M guest instructions).
    let mut two = araim_common::sky(24, 0, 100.0);
    two.obs[23].residual_m -= 100.0;
    let r = t.ask(epoch_command(11.0, &two.obs), "sky24 two faults");
    let w = result(&r);
    assert!(matches!(w.fde, WireFde::Excluded { .. }), "{:?}", w.fde);
    assert_eq!(w.excluded.as_slice(), &[two.obs[0].id, two.obs[23].id]);
    assert_eq!(w.decision, Decision::Excluded);

    // The same two faults on 32 satellites (563 modes): stage 2 would
    // process every monitored mode as a candidate, 347 M guest
    // instructions (~3.1 s at 168 MHz, beyond the 2 s watchdog); the
    // server's work budget (`FDE_WORK_BUDGET / monitored` candidates)
    // refuses it after stage 1: an `Alarm` with `BudgetExceeded` on the
    // wire, bit for bit with the host, never a pass (~96 M instructions,
    // BENCHMARKS.md).
    let mut two = araim_common::sky(32, 0, 100.0);
    two.obs[31].residual_m -= 100.0;
    t.ask(two.ism_command(), "sky32 ISM");
    let r = t.ask(epoch_command(12.0, &two.obs), "sky32 two faults");
    let w = result(&r);
    assert_eq!(w.all_in_view.modes, 563);
    let m = w.all_in_view.monitored;
    assert_eq!(
        w.fde,
        WireFde::BudgetExceeded {
            candidates: m,
            budget: raim_server::araim::FDE_WORK_BUDGET / m,
        }
    );
    assert!(m > raim_server::araim::FDE_WORK_BUDGET / m);
    assert_eq!(w.decision, Decision::Alarm);
    assert!(w.excluded.is_empty() && w.after_exclusion.is_none());
    // Every ARAIM epoch wrote its sentences, the device's the host's.
    assert!(t.check_nmea() > 0);
}

/// The bad inputs over the wire: typed errors equal to the host's,
/// the good ISM stays in force, every frame answered and counted, no reset.
///
/// Verifies: WIRE-Araim, WIRE-Locked
#[test]
fn qemu_araim_bad_input_is_typed_and_nothing_is_lost() {
    let mut t = Twin::new(qemu_common::session());
    let s = sky20(usize::MAX, 0.0);
    let r = t.ask(epoch_command(0.0, &s.obs), "epoch before any ISM");
    assert_eq!(*error(&r), WireError::Araim(AraimWireError::NoIsm));
    t.ask(s.ism_command(), "good ISM");
    let good = t.ask(epoch_command(1.0, &s.obs), "good epoch");
    let bad_isms: Vec<BadIsm> = {
        let with = |f: &dyn Fn(&mut Vec<IsmSat>)| {
            let mut v = s.ism.clone();
            f(&mut v);
            v
        };
        let mut beidou = s.p_const;
        beidou[System::Beidou.index()] = Some(1e-4);
        vec![
            (
                "NaN sigma_URA",
                with(&|v| v[3].sigma_ura_m = f64::NAN),
                s.p_const,
            ),
            ("P_sat 0", with(&|v| v[4].p_sat = 0.0), s.p_const),
            ("P_sat 1", with(&|v| v[5].p_sat = 1.0), s.p_const),
            ("constellation without satellites", s.ism.clone(), beidou),
            (
                "40 satellites",
                (0..40u8)
                    .map(|k| IsmSat {
                        id: SatId::new(System::Gps, k + 1),
                        ..s.ism[0]
                    })
                    .collect(),
                s.p_const,
            ),
            ("duplicate PRN", with(&|v| v[9].id = v[2].id), s.p_const),
        ]
    };
    let mut errors = 1;
    for (what, ism, p_const) in &bad_isms {
        let cmd = CommandRef::Araim(raim_proto::araim_msg::AraimCommandRef::Ism(
            raim_proto::araim_msg::IsmFrameRef {
                config: s.config,
                p_const: *p_const,
                sats: ism,
            },
        ));
        let r = t.ask(cmd, what);
        assert!(matches!(r.body, ResponseBody::Error(_)), "{what}: {r:?}");
        errors += 1;
    }
    let mut dup = s.obs.clone();
    dup[9].id = dup[2].id;
    let mut stranger = s.obs.clone();
    stranger[8].id = SatId::new(System::Gps, 30);
    let mut nan = s.obs.clone();
    nan[4].residual_m = f64::NAN;
    let forty: Vec<_> = (0..40).map(|k| s.obs[k % 20]).collect();
    for (what, obs) in [
        ("duplicate PRN epoch", &dup),
        ("satellite without ISM entry", &stranger),
        ("NaN residual", &nan),
        ("40 satellites epoch", &forty),
    ] {
        let r = t.ask(epoch_command(3.0, obs), what);
        assert!(matches!(r.body, ResponseBody::Error(_)), "{what}: {r:?}");
        errors += 1;
    }
    // The good ISM stayed in force.
    let again = t.ask(epoch_command(1.0, &s.obs), "good epoch again");
    assert_eq!(result(&again), result(&good));
    // Locked: an ISM frame is refused, typed, like the host's.
    t.ask(CommandRef::Lock, "lock");
    let r = t.ask(s.ism_command(), "ISM after lock");
    assert!(matches!(error(&r), WireError::Locked { .. }));
    errors += 1;
    // Refused epochs wrote their no-fix sentences, the device's the host's.
    assert!(t.check_nmea() > 0);
    let st = t.fw.status().unwrap();
    assert_eq!(st.frames, t.fw.next_seq());
    assert_eq!(st.errors, errors);
    assert_eq!(st.resets, 0);
}

/// The f32 device engine against the f64 core on the exact roots of the
/// PLs, EMT and sigma_v,acc: `f32_agrees_with_f64` (raim-core) bounds the
/// engines' spread by 2e-4 relative; plus 1 mm.
const F32_REL_TOL: f64 = 2e-4;
const F32_ABS_TOL_M: f64 = 1e-3;
/// The device's position against the f64 one (m): the f32 subset solution
/// of a few metres of residuals, and the f32 Gauss-Newton's stopping point
/// (within its 1.2 cm rounding floor, compensated to first order by the
/// correction S0 y).
const POSITION_TOL_M: f64 = 0.005;
/// The position in force against the truth (m): the scenario's residuals
/// are within +-0.15 m.
const TRUTH_TOL_M: f64 = 1.0;

/// The independent host number for a pseudorange ARAIM epoch: the f64 core
/// (`Araim<f64>` and its FDE) on the epoch linearised here at the *true*
/// receiver position and clocks (not the device's Gauss-Newton point), with
/// C_int/C_acc from `error_model::variances_m2`. Returns the FDE decision,
/// the exact VPL/HPL, EMT and sigma_v,acc of the all-in-view run, those of
/// the solution in force, and its ECEF position.
#[allow(clippy::type_complexity)]
fn f64_reference(
    s: &Scenario,
    ranges: &[RangeObservation],
) -> (FdeDecision, [f64; 4], Option<[f64; 4]>, [f64; 3]) {
    let x = araim_common::RECEIVER_ECEF_M;
    let rot = enu_rotation(&ecef_to_geodetic(x));
    let sats: Vec<AraimSat<f64>> = ranges
        .iter()
        .map(|o| {
            let d = [
                o.position_m[0] - x[0],
                o.position_m[1] - x[1],
                o.position_m[2] - x[2],
            ];
            let rho = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let u = rotate(&rot, [d[0] / rho, d[1] / rho, d[2] / rho]);
            let e = s.ism.iter().find(|e| e.id == o.id).unwrap();
            let el = u[2].asin();
            let (c_int, c_acc) = error_model::variances_m2(el, e.sigma_ura_m, e.sigma_ure_m);
            AraimSat {
                id: o.id,
                g_enu: [-u[0], -u[1], -u[2]],
                c_int_m2: c_int,
                c_acc_m2: c_acc,
                b_nom_m: e.b_nom_m,
                p_sat: e.p_sat,
                residual_m: o.pseudorange_m - rho - araim_common::CLOCK_M[o.id.system.index()],
            }
        })
        .collect();
    let cfg = AraimConfig::from(s.config);
    let ism = Ism { p_const: s.p_const };
    let mut main = Box::new(Araim::<f64, 32, 1024>::new());
    let mut scratch = Box::new(Araim::<f64, 32, 1024>::new());
    let out = main.process(&cfg, &ism, &sats).unwrap();
    let nums = |o: &raim_core::araim::AraimOutput<f64, 1024>| {
        [o.pl_exact.vpl_m, o.pl_exact.hpl_m, o.emt_m, o.sigma_v_acc_m]
    };
    let all = nums(out);
    let mut correction = out.correction_enu_m;
    let d = main.fde(&cfg, &ism, &sats, &mut scratch).unwrap();
    let after = match d {
        FdeDecision::Excluded { .. } => {
            correction = scratch.output().correction_enu_m;
            Some(nums(scratch.output()))
        }
        _ => None,
    };
    let shift = unrotate(&rot, correction);
    (
        d,
        all,
        after,
        [x[0] + shift[0], x[1] + shift[1], x[2] + shift[2]],
    )
}

fn close(device: f64, reference: f64) -> bool {
    (device - reference).abs() <= F32_ABS_TOL_M + F32_REL_TOL * reference.abs()
}

fn distance_m(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Checks a device result on a pseudorange epoch against `f64_reference`.
fn check_against_f64(w: &WireAraimResult, s: &Scenario, ranges: &[RangeObservation], what: &str) {
    let (d, all, after, position) = f64_reference(s, ranges);
    let got = |a: &raim_proto::araim_msg::AraimSummary| {
        [a.vpl_exact_m, a.hpl_exact_m, a.emt_m, a.sigma_v_acc_m]
    };
    let a = got(&w.all_in_view);
    for k in 0..4 {
        assert!(
            close(a[k], all[k]),
            "{what}: all in view {a:?} vs f64 {all:?}"
        );
    }
    match (d, &w.fde) {
        (FdeDecision::NoFault, WireFde::NoFault) => {}
        (FdeDecision::Excluded { mode, sats, .. }, WireFde::Excluded { mode: m, .. }) => {
            assert_eq!(mode as u32, *m, "{what}");
            let ids: Vec<SatId> = (0..ranges.len())
                .filter(|i| sats & (1 << i) != 0)
                .map(|i| ranges[i].id)
                .collect();
            assert_eq!(w.excluded.as_slice(), ids.as_slice(), "{what}");
            let (b, r) = (got(w.after_exclusion.as_ref().unwrap()), after.unwrap());
            for k in 0..4 {
                assert!(
                    close(b[k], r[k]),
                    "{what}: after exclusion {b:?} vs f64 {r:?}"
                );
            }
        }
        (FdeDecision::Alarm(raim_core::araim::FdeAlarm::NoCandidate), WireFde::NoCandidate)
        | (
            FdeDecision::Alarm(raim_core::araim::FdeAlarm::Ambiguous { .. }),
            WireFde::Ambiguous { .. },
        ) => {}
        (want, got) => panic!("{what}: device {got:?}, f64 {want:?}"),
    }
    let p = w.position_ecef_m.expect("a pseudorange epoch's position");
    let dp = distance_m(p, position);
    eprintln!(
        "{what}: {:?} {:?}, VPL {:.3} (f64 {:.3}) m, position - f64 {:.2e} m, - truth {:.3} m",
        w.decision,
        w.fde,
        w.in_force().vpl_exact_m,
        after.unwrap_or(all)[0],
        dp,
        distance_m(p, araim_common::RECEIVER_ECEF_M)
    );
    assert!(dp <= POSITION_TOL_M, "{what}: {p:?} vs f64 {position:?}");
    assert!(
        distance_m(p, araim_common::RECEIVER_ECEF_M) <= TRUTH_TOL_M,
        "{what}: {p:?}"
    );
}

/// ARAIM from pseudorange epochs (protocol 8): the device linearises the
/// epoch itself (Gauss-Newton all in view), bit for bit with the host
/// `Server`; each result is checked against the f64 core on the epoch
/// linearised at the truth (same decision and excluded set, PLs within
/// the f32 tolerance, position within 5 mm of the f64 one and within the
/// noise of the truth): a clean G10+E10 sky, 100 m on one satellite
/// (excluded), and bad input (NaN pseudorange, too few satellites).
#[test]
fn qemu_araim_pseudorange_epochs_match_the_host_and_the_f64_core() {
    let mut t = Twin::new(qemu_common::session());
    let clean = sky20(usize::MAX, 0.0);
    t.ask(clean.ism_command(), "sky20 ISM");
    let ranges = ranges_of(&clean);
    let r = t.ask(ranges_command(1.0, &ranges), "sky20 clean, ranges");
    let w = result(&r);
    assert_eq!(w.decision, Decision::Ok);
    check_against_f64(w, &clean, &ranges, "clean");
    let mut excluded = 0;
    for faulty in [3, 8] {
        let s = sky20(faulty, 100.0);
        let ranges = ranges_of(&s);
        let what = format!("sky20 100 m on {faulty}, ranges");
        let r = t.ask(ranges_command(2.0, &ranges), &what);
        let w = result(&r);
        assert!(!w.all_in_view.detection_passed, "{what}");
        check_against_f64(w, &s, &ranges, &what);
        if matches!(w.fde, WireFde::Excluded { .. }) {
            assert_eq!(w.excluded.as_slice(), &[s.obs[faulty].id]);
            excluded += 1;
        }
    }
    assert!(excluded >= 1, "no exclusion");
    // Bad input: typed errors, the same as the host's.
    let mut nan = ranges.clone();
    nan[4].pseudorange_m = f64::NAN;
    let r = t.ask(ranges_command(3.0, &nan), "NaN pseudorange");
    assert!(
        matches!(error(&r), WireError::NonFinite { .. }),
        "{:?}",
        error(&r)
    );
    let r = t.ask(ranges_command(4.0, &ranges[..4]), "four satellites");
    assert!(
        matches!(error(&r), WireError::TooFewSatellites { .. }),
        "{:?}",
        error(&r)
    );
    // Pseudorange epochs' sentences carry the position, the device's the
    // host's.
    assert!(t.check_nmea() > 0);
    let st = t.fw.status().unwrap();
    assert_eq!(st.resets, 0);
}
