//! ARAIM (issue 12) in the firmware under QEMU (mps2-an386): ISM frames and
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

use araim_common::{appendix_d, epoch_command, sky20, Twin};
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
    // Seed 003's N* on the device (issue 13): App. D's vertical N* from
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
    assert!(t.fw.drain_nmea().is_empty(), "ARAIM writes no NMEA");
}

/// The bad inputs over the wire: typed errors equal to the host's,
/// the good ISM stays in force, every frame answered and counted, no reset.
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
    let st = t.fw.status().unwrap();
    assert_eq!(st.frames, t.fw.next_seq());
    assert_eq!(st.errors, errors);
    assert_eq!(st.resets, 0);
}
