//! The ARAIM bounds: each field's ends accepted and just outside refused,
//! the ADD's values inside, the attack values of the configuration
//! authority review refused, and the module's property (every single
//! event listed) by proptest over random skies and accepted ISMs.
extern crate std;
use super::*;
use crate::araim::modes::{self, EnumerationLimit, Events, ModeEvents};
use crate::araim::tests::random_sky;
use crate::araim::{Araim, AraimConfig, AraimSat, Ism, ModeStatus, Unavailable};
use crate::measurement::{SatId, System};
use crate::result::Decision;
use proptest::prelude::*;
use std::vec::Vec;

fn oor(b: Bound, index: usize, value: f64) -> AraimError {
    AraimError::OutOfRange {
        field: b.field,
        index,
        value,
        min: b.min,
        max: b.max,
    }
}

/// Both ends and the middle pass, just outside fails (NaN and infinities
/// are `NotFinite`, checked by the callers first).
fn float_bound(b: Bound, check: impl Fn(f64) -> Result<(), AraimError>, index: usize) {
    assert!(b.min < b.max, "{}", b.field);
    for v in [b.min, b.max, 0.5 * (b.min + b.max)] {
        assert_eq!(check(v), Ok(()), "{} = {v}", b.field);
    }
    let below = if b.min > 0.0 { b.min * 0.999 } else { -1e-12 };
    for v in [below, b.max * 1.001] {
        assert_eq!(check(v), Err(oor(b, index, v)), "{} = {v}", b.field);
    }
    for v in [f64::NAN, f64::INFINITY] {
        assert!(
            matches!(check(v), Err(AraimError::NotFinite { field, .. }) if field == b.field),
            "{} = {v}",
            b.field
        );
    }
}

/// A configuration whose cross-field rules hold at every corner of the
/// one field being varied (P_THRES below the smallest PHMI sum; the EMT
/// limit below the smallest VAL).
fn roomy() -> AraimConfig {
    AraimConfig {
        phmi_vert: PHMI_VERT.max,
        phmi_hor: PHMI_HOR.max,
        p_thres: P_THRES.min,
        emt_max_m: EMT_MAX_M.min,
        val_m: VAL_M.max,
        ..AraimConfig::default()
    }
}

fn cfg_bound(b: Bound, set: fn(&mut AraimConfig, f64)) {
    float_bound(
        b,
        |v| {
            let mut c = roomy();
            set(&mut c, v);
            c.validate()
        },
        0,
    );
}

#[test]
fn every_configuration_field_is_bounded() {
    cfg_bound(PHMI_VERT, |c, v| c.phmi_vert = v);
    cfg_bound(PHMI_HOR, |c, v| c.phmi_hor = v);
    cfg_bound(PFA_VERT, |c, v| c.pfa_vert = v);
    cfg_bound(PFA_HOR, |c, v| c.pfa_hor = v);
    cfg_bound(P_THRES, |c, v| c.p_thres = v);
    cfg_bound(P_EMT, |c, v| c.p_emt = v);
    cfg_bound(VAL_M, |c, v| c.val_m = v);
    cfg_bound(HAL_M, |c, v| c.hal_m = v);
    cfg_bound(TOL_PL_M, |c, v| c.tol_pl_m = v);
    cfg_bound(EMT_MAX_M, |c, v| {
        c.emt_max_m = v;
        c.val_m = VAL_M.max;
    });
    cfg_bound(SIGMA_ACC_MAX_M, |c, v| c.sigma_acc_max_m = v);
}

fn sat() -> AraimSat<f64> {
    let (c_int, c_acc) = crate::araim::error_model::variances_m2(0.6f64, 0.75, 0.5);
    AraimSat {
        id: SatId::new(System::Gps, 1),
        g_enu: AraimSat::g_from_az_el(0.3, 0.6),
        c_int_m2: c_int,
        c_acc_m2: c_acc,
        b_nom_m: 0.5,
        p_sat: 1e-5,
        residual_m: 0.0,
    }
}

/// Verifies: SAFE-T1
#[test]
fn every_ism_field_is_bounded() {
    let sat_bound = |b: Bound, set: fn(&mut AraimSat<f64>, f64)| {
        float_bound(
            b,
            |v| {
                let mut s = sat();
                set(&mut s, v);
                s.validate(4)
            },
            4,
        )
    };
    sat_bound(P_SAT, |s, v| s.p_sat = v);
    sat_bound(B_NOM_M, |s, v| s.b_nom_m = v);
    sat_bound(C_INT_M2, |s, v| {
        s.c_int_m2 = v;
        s.c_acc_m2 = C_ACC_M2.min;
    });
    sat_bound(C_ACC_M2, |s, v| {
        s.c_acc_m2 = v;
        s.c_int_m2 = C_INT_M2.max;
    });
    // C_acc above C_int.
    let mut s = sat();
    s.c_acc_m2 = s.c_int_m2 * 1.01;
    assert!(matches!(
        s.validate(2),
        Err(AraimError::OutOfRange { field: "c_acc_m2", index: 2, max, .. }) if max == s.c_int_m2
    ));
    // A geometry row that is not a unit line of sight.
    let mut s = sat();
    s.g_enu = s.g_enu.map(|v| 2.0 * v);
    assert!(matches!(
        s.validate(0),
        Err(AraimError::OutOfRange {
            field: "g_norm",
            ..
        })
    ));
    // P_const.
    float_bound(
        P_CONST,
        |v| {
            let mut ism = Ism::with(&[System::Gps], 1e-4);
            ism.p_const[System::Galileo.index()] = Some(v);
            ism.validate()
        },
        System::Galileo.index(),
    );
    // The protocol's per-satellite entry: sigma_URA, sigma_URE <= URA.
    float_bound(
        SIGMA_URA_M,
        |v| check_ism_entry(3, v, SIGMA_URE_M.min, 0.5, 1e-5),
        3,
    );
    float_bound(
        SIGMA_URE_M,
        |v| check_ism_entry(3, SIGMA_URA_M.max, v, 0.5, 1e-5),
        3,
    );
    assert_eq!(
        check_ism_entry(1, 0.75, 0.8, 0.5, 1e-5),
        Err(AraimError::OutOfRange {
            field: "sigma_ure_m",
            index: 1,
            value: 0.8,
            min: SIGMA_URE_M.min,
            max: 0.75
        })
    );
    assert_eq!(check_ism_entry(1, 0.75, 0.5, 0.75, 1e-5), Ok(()));
}

/// The bounds' own derived ends: C_int's floor is what the floors give,
/// and the ADD model's smallest variance (zenith) is above the host-sigma
/// floor's square, so the model never needs a value the bound refuses.
#[test]
fn variance_bounds_follow_from_the_sigma_bounds() {
    let zenith = crate::araim::error_model::nominal_variance_m2(core::f64::consts::FRAC_PI_2);
    assert!(zenith >= SIGMA_M.min * SIGMA_M.min, "{zenith}");
    let horizon = crate::araim::error_model::nominal_variance_m2(0.0f64);
    assert!(horizon <= SIGMA_M.max * SIGMA_M.max, "{horizon}");
    let (lo, _) = crate::araim::error_model::variances_m2(
        core::f64::consts::FRAC_PI_2,
        SIGMA_URA_M.min,
        SIGMA_URE_M.min,
    );
    assert!(lo >= C_INT_M2.min);
}

/// The ADD's LPV-200 configuration and the Appendix D ISM are accepted.
#[test]
fn the_add_values_are_inside() {
    assert_eq!(AraimConfig::default().validate(), Ok(()));
    for p in [1e-5, 3e-5] {
        assert_eq!(P_SAT.check_araim(0, p), Ok(()));
    }
    for p in [1e-4, 1e-8] {
        assert_eq!(P_CONST.check_araim(0, p), Ok(()));
    }
    assert_eq!(check_ism_entry(0, 0.75, 0.5, 0.75, 1e-5), Ok(()));
    assert_eq!(check_ism_entry(0, 0.75, 0.5, 0.5, 1e-5), Ok(()));
}

/// The values of the configuration-authority review, each refused with
/// its field: P_sat = P_const = 1e-300 (0 fault modes, `Ok` with VPL
/// 10.6 m over a 123.5 m error), PHMI near 1 with P_THRES 0.9, Pfa
/// 1e-300, limits of 1e300.
///
/// Verifies: SAFE-T1
#[test]
fn the_attack_values_are_refused() {
    let mut s = sat();
    s.p_sat = 1e-300;
    assert_eq!(s.validate(0), Err(oor(P_SAT, 0, 1e-300)));
    assert_eq!(
        Ism::with(&[System::Gps], 1e-300).validate(),
        Err(oor(P_CONST, System::Gps.index(), 1e-300))
    );
    let near_one = 1.0 - 1e-9;
    let c = AraimConfig {
        phmi_vert: near_one,
        phmi_hor: near_one,
        p_thres: 0.9,
        ..AraimConfig::default()
    };
    assert_eq!(c.validate(), Err(oor(PHMI_VERT, 0, near_one)));
    let c = AraimConfig {
        p_thres: 0.9,
        ..AraimConfig::default()
    };
    assert_eq!(c.validate(), Err(oor(P_THRES, 0, 0.9)));
    for (b, set) in [
        (
            PFA_VERT,
            (|c, v| c.pfa_vert = v) as fn(&mut AraimConfig, f64),
        ),
        (PFA_HOR, |c, v| c.pfa_hor = v),
    ] {
        let mut c = AraimConfig::default();
        set(&mut c, 1e-300);
        assert_eq!(c.validate(), Err(oor(b, 0, 1e-300)));
    }
    for (b, set) in [
        (VAL_M, (|c, v| c.val_m = v) as fn(&mut AraimConfig, f64)),
        (HAL_M, |c, v| c.hal_m = v),
        (EMT_MAX_M, |c, v| c.emt_max_m = v),
        (SIGMA_ACC_MAX_M, |c, v| c.sigma_acc_max_m = v),
    ] {
        let mut c = AraimConfig::default();
        set(&mut c, 1e300);
        assert_eq!(c.validate(), Err(oor(b, 0, 1e300)));
    }
    // An EMT limit above the VAL is no limit.
    let c = AraimConfig {
        emt_max_m: 40.0,
        val_m: 35.0,
        ..AraimConfig::default()
    };
    assert_eq!(
        c.validate(),
        Err(AraimError::OutOfRange {
            field: "emt_max_m",
            index: 0,
            value: 40.0,
            min: EMT_MAX_M.min,
            max: 35.0
        })
    );
}

/// A value in `b` on a log scale from `u` in [0, 1]; 0 and 1 are the ends.
fn log_in(b: Bound, u: f64) -> f64 {
    let v = libm::exp(libm::log(b.min) + u * (libm::log(b.max) - libm::log(b.min)));
    v.clamp(b.min, b.max)
}

/// A corner (0 or 1) a third of the time each end, else uniform.
fn corner_or_uniform() -> impl Strategy<Value = f64> {
    prop_oneof![Just(0.0), Just(1.0), 0.0f64..=1.0]
}

/// The events of a sky for the enumeration.
struct SkyEvents {
    p_sat: Vec<f64>,
    sat_system: Vec<u8>,
    p_const: Vec<(u8, f64)>,
}

impl SkyEvents {
    fn events(&self) -> Events<'_> {
        Events {
            p_sat: &self.p_sat,
            sat_system: &self.sat_system,
            p_const: &self.p_const,
        }
    }
}

/// Every single satellite and every constellation is a mode of `list`.
fn every_single_event_listed(list: &[ModeEvents], n: usize, consts: &[(u8, f64)]) -> bool {
    (0..n).all(|i| list.iter().any(|m| m.sats == 1u64 << i && m.consts == 0))
        && consts
            .iter()
            .all(|&(j, _)| list.iter().any(|m| m.sats == 0 && m.consts == 1u8 << j))
}

const SYSTEMS: [System; 3] = [System::Gps, System::Galileo, System::Beidou];

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// THE PROPERTY, on the enumeration: for any sky of 5-32 satellites
    /// over 1-3 constellations, any P_sat per satellite and P_const per
    /// constellation within their bounds and any P_THRES within its bound
    /// (ends included), the mode list holds every single-satellite and
    /// every constellation mode with N_fault,max >= 1, or the epoch is
    /// refused as a whole with a typed limit (capacity, too many events)
    /// whose list is empty (never truncated).
    #[test]
    fn every_single_event_is_enumerated(
        n in 5usize..=32,
        nc in 1usize..=3,
        p_sat_u in proptest::collection::vec(corner_or_uniform(), 32),
        p_const_u in proptest::collection::vec(corner_or_uniform(), 3),
        p_thres_u in corner_or_uniform(),
        systems in proptest::collection::vec(0usize..3, 32),
    ) {
        let sky = SkyEvents {
            p_sat: p_sat_u.iter().take(n).map(|&u| log_in(P_SAT, u)).collect(),
            // Each constellation in use gets at least one satellite.
            sat_system: (0..n)
                .map(|i| SYSTEMS[if i < nc { i } else { systems[i] % nc }].index() as u8)
                .collect(),
            p_const: (0..nc)
                .map(|j| (SYSTEMS[j].index() as u8, log_in(P_CONST, p_const_u[j])))
                .collect(),
        };
        let p_thres = log_in(P_THRES, p_thres_u);
        let mut list: heapless::Vec<ModeEvents, 1024> = heapless::Vec::new();
        match modes::enumerate(&sky.events(), p_thres, &mut list) {
            Ok(e) => {
                prop_assert!(e.max_faults >= 1, "{e:?}");
                prop_assert!(every_single_event_listed(&list, n, &sky.p_const));
                prop_assert_eq!(list.len(), e.needed);
            }
            Err(EnumerationLimit::Capacity { needed, capacity }) => {
                prop_assert!(needed > capacity && list.is_empty());
            }
            Err(EnumerationLimit::TooManyEvents { p_exceed_at_max }) => {
                prop_assert!(p_exceed_at_max > p_thres && list.is_empty());
            }
        }
    }
}

/// A random accepted configuration: every field log-uniform (or at an end)
/// in its bound, the cross-field rules met.
fn accepted_config(u: &[f64]) -> AraimConfig {
    let phmi_vert = log_in(PHMI_VERT, u[0]);
    let phmi_hor = log_in(PHMI_HOR, u[1]);
    let thres = Bound {
        max: P_THRES.max.min(0.999 * (phmi_vert + phmi_hor)),
        ..P_THRES
    };
    let val_m = log_in(VAL_M, u[6]);
    let emt = Bound {
        max: EMT_MAX_M.max.min(val_m),
        ..EMT_MAX_M
    };
    AraimConfig {
        phmi_vert,
        phmi_hor,
        pfa_vert: log_in(PFA_VERT, u[2]),
        pfa_hor: log_in(PFA_HOR, u[3]),
        p_thres: log_in(thres, u[4]),
        p_emt: log_in(P_EMT, u[5]),
        val_m,
        hal_m: log_in(HAL_M, u[7]),
        tol_pl_m: log_in(TOL_PL_M, u[8]),
        emt_max_m: log_in(emt, u[9]),
        sigma_acc_max_m: log_in(SIGMA_ACC_MAX_M, u[10]),
        ..AraimConfig::default()
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    /// THE PROPERTY, through the engine: random skies of 5-32 satellites
    /// (ADD error model), random accepted ISMs and configurations. The
    /// epoch is accepted (every input within its bound) and either every
    /// single-satellite and constellation mode is in the output, each
    /// monitored or with its prior in P_unmon (and the epoch `Unmonitored`
    /// when that exceeds P_THRES), or the epoch is unavailable with a typed
    /// enumeration limit; `Ok` only in the first case.
    #[test]
    fn no_accepted_ism_drops_a_single_event_from_monitoring(
        seed in 0u64..1_000_000,
        n in 5usize..=32,
        nc in 1usize..=3,
        p_sat_u in proptest::collection::vec(corner_or_uniform(), 32),
        p_const_u in proptest::collection::vec(corner_or_uniform(), 3),
        cfg_u in proptest::collection::vec(corner_or_uniform(), 11),
        b_nom_u in corner_or_uniform(),
    ) {
        // At least one redundant satellite: 3 + clocks < n.
        let nc = nc.min(n - 4);
        let mut rng = crate::testutil::Rng::new(seed);
        let mut sats = random_sky(&mut rng, n, &SYSTEMS[..nc], 1e-5);
        for (s, &u) in sats.iter_mut().zip(p_sat_u.iter()) {
            s.p_sat = log_in(P_SAT, u);
            s.b_nom_m = B_NOM_M.min + b_nom_u * (B_NOM_M.max - B_NOM_M.min);
        }
        let mut ism = Ism::default();
        for (j, sys) in SYSTEMS.iter().take(nc).enumerate() {
            ism.p_const[sys.index()] = Some(log_in(P_CONST, p_const_u[j]));
        }
        let cfg = accepted_config(&cfg_u);
        prop_assert_eq!(cfg.validate(), Ok(()));
        let mut engine = Araim::<f64, 32, 1024>::new();
        let out = engine.process(&cfg, &ism, &sats);
        // A random sky may be singular; that is a typed refusal too.
        let out = match out {
            Err(AraimError::RankDeficient { .. }) => return Ok(()),
            other => other.unwrap(),
        };
        match out.unavailable {
            Some(Unavailable::ModeCapacity { .. } | Unavailable::TooManyEvents { .. }) => {
                prop_assert!(out.modes.is_empty());
                prop_assert!(out.decision() != Decision::Ok);
                prop_assert_eq!(out.pl_add.vpl_m, f64::INFINITY);
            }
            _ => {
                prop_assert!(out.max_faults >= 1);
                let list: Vec<ModeEvents> = out.modes.iter().map(|m| m.events).collect();
                let consts: Vec<(u8, f64)> = (0..nc)
                    .map(|j| (SYSTEMS[j].index() as u8, 0.0))
                    .collect();
                prop_assert!(every_single_event_listed(&list, n, &consts));
                let unmonitorable: f64 = out
                    .modes
                    .iter()
                    .filter(|m| m.status != ModeStatus::Monitored)
                    .map(|m| m.events.prior)
                    .sum();
                prop_assert!(out.p_unmon >= unmonitorable * (1.0 - 1e-12));
                if out.p_unmon > cfg.p_thres {
                    let unmonitored = matches!(out.unavailable, Some(Unavailable::Unmonitored { .. }));
                    prop_assert!(unmonitored, "{:?}", out.unavailable);
                    prop_assert!(out.decision() != Decision::Ok);
                }
            }
        }
    }
}

/// The review's sky: 0 fault modes at P_sat = P_const = 1e-300 is no
/// longer reachable, and at the bounds' lowest priors the engine lists
/// every single event of an 8-satellite GPS sky.
#[test]
fn lowest_priors_still_list_every_single_event() {
    let mut rng = crate::testutil::Rng::new(23);
    let mut sats = random_sky(&mut rng, 8, &[System::Gps], P_SAT.min);
    let ism = Ism::with(&[System::Gps], P_CONST.min);
    let cfg = AraimConfig {
        p_thres: P_THRES.max,
        ..AraimConfig::default()
    };
    let mut engine = Araim::<f64, 16, 256>::new();
    let out = engine.process(&cfg, &ism, &sats).unwrap();
    assert_eq!(out.max_faults, 1);
    assert_eq!(out.modes.len(), 9, "8 satellites + GPS");
    sats[0].p_sat = 1e-300;
    assert_eq!(
        engine.process(&cfg, &ism, &sats).unwrap_err(),
        oor(P_SAT, 0, 1e-300)
    );
}

/// The Appendix D satellites (SPEC §9.1) with `residual_m` per satellite.
fn appendix_d_with(residual_m: [f64; 10]) -> Vec<AraimSat<f64>> {
    crate::araim::tests::appendix_d::ROWS
        .iter()
        .zip(residual_m)
        .enumerate()
        .map(|(i, (r, y))| AraimSat {
            id: SatId::new(
                if i < 5 { System::Gps } else { System::Galileo },
                (i % 5 + 1) as u8,
            ),
            g_enu: r.g,
            c_int_m2: r.c_int,
            c_acc_m2: r.c_acc,
            b_nom_m: 0.5,
            p_sat: 1e-5,
            residual_m: y,
        })
        .collect()
}

/// An epoch that stops before the PL equations reports +infinity, never 0:
/// here a GPS-only sky whose constellation mode is unmonitorable with
/// P_const 1e-4 > P_THRES (`Unmonitored`).
#[test]
fn an_unavailable_epoch_reports_unbounded_pls() {
    let sats: Vec<AraimSat<f64>> = appendix_d_with([0.0; 10]).into_iter().take(5).collect();
    let mut engine = Araim::<f64, 16, 256>::new();
    let out = engine
        .process(
            &AraimConfig::default(),
            &Ism::with(&[System::Gps], 1e-4),
            &sats,
        )
        .unwrap();
    assert!(matches!(
        out.unavailable,
        Some(Unavailable::Unmonitored { .. })
    ));
    for pl in [out.pl_add, out.pl_exact] {
        assert_eq!(pl, crate::araim::ProtectionLevels::UNBOUNDED);
    }
    assert_eq!(out.decision(), Decision::Unavailable);
}

/// The review's case: an epoch unavailable after an exclusion reported
/// VPL/HPL 0.00. A ramp of 0-120 m on the Galileo satellites (not a common
/// offset, which the Galileo clock would absorb) is explained only by the
/// Galileo constellation's fault; the GPS-only subset left has its own
/// constellation mode unmonitorable, so it is unavailable, and its PLs are
/// +infinity.
#[test]
fn unavailable_after_an_exclusion_reports_unbounded_pls() {
    let sats = appendix_d_with([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 30.0, 60.0, 90.0, 120.0]);
    let ism = Ism::with(&[System::Gps, System::Galileo], 1e-4);
    let cfg = AraimConfig::default();
    let mut main = Araim::<f64, 16, 256>::new();
    let mut scratch = Araim::<f64, 16, 256>::new();
    assert!(!main.process(&cfg, &ism, &sats).unwrap().detection_passed);
    let d = main.fde(&cfg, &ism, &sats, &mut scratch).unwrap();
    let galileo = 1u8 << System::Galileo.index();
    assert!(
        matches!(d, crate::araim::FdeDecision::Excluded { consts, sats, .. } if consts == galileo && sats == 0b11111_00000),
        "{d:?}"
    );
    let sub = scratch.output();
    assert!(
        matches!(sub.unavailable, Some(Unavailable::Unmonitored { .. })),
        "{:?}",
        sub.unavailable
    );
    assert_eq!(sub.pl_add, crate::araim::ProtectionLevels::UNBOUNDED);
    assert_eq!(sub.pl_exact, crate::araim::ProtectionLevels::UNBOUNDED);
}

/// Issue 35: C_int and C_acc are held against their bounds in the
/// precision they are formed in. In f32 the floors' C_acc (0.2² + 0.3² m²)
/// is 0.1299999952 m², below the f64 bound 0.13 m²; it is accepted against
/// the bound rounded to f32, and so is every combination of the floors
/// with itself and with the ceilings; the f32 value just below the rounded
/// floor (and just above the rounded ceiling) is refused, carrying the
/// bound as the check saw it.
///
/// Verifies: SAFE-BOUNDS-PRECISION
#[test]
fn derived_variances_are_checked_in_the_engines_precision() {
    let sq = |a: f64, b: f64| a * a + b * b;
    let (ura, ure, sig) = (SIGMA_URA_M, SIGMA_URE_M, SIGMA_M);
    assert_eq!(C_ACC_M2.min, sq(ure.min, sig.min));
    assert_eq!(C_INT_M2.min, sq(ura.min, sig.min));
    assert!(f64::from(sq(ure.min, sig.min) as f32) < C_ACC_M2.min);
    let base = AraimSat::<f32> {
        id: SatId::new(System::Gps, 1),
        g_enu: [0.0, 0.0, -1.0],
        c_int_m2: 1.0,
        c_acc_m2: 0.5,
        b_nom_m: 0.5,
        p_sat: 1e-5,
        residual_m: 0.0,
    };
    let mut n = 0;
    for u in [ura.min, ura.max] {
        for e in [ure.min, ure.max].into_iter().filter(|e| *e <= u) {
            for s in [sig.min, sig.max] {
                let sat = AraimSat::<f32> {
                    c_int_m2: sq(u, s) as f32,
                    c_acc_m2: sq(e, s) as f32,
                    ..base
                };
                assert_eq!(sat.validate(3), Ok(()), "{u} {e} {s}");
                n += 1;
            }
        }
    }
    assert_eq!(n, 6);
    let floor = C_ACC_M2.min as f32;
    let below = f32::from_bits(floor.to_bits() - 1);
    let low = AraimSat::<f32> {
        c_acc_m2: below,
        ..base
    };
    assert_eq!(
        low.validate(3),
        Err(AraimError::OutOfRange {
            field: "c_acc_m2",
            index: 3,
            value: f64::from(below),
            min: f64::from(floor),
            max: f64::from(C_ACC_M2.max as f32)
        })
    );
    let ceiling = C_INT_M2.max as f32;
    let high = AraimSat::<f32> {
        c_int_m2: f32::from_bits(ceiling.to_bits() + 1),
        ..base
    };
    assert!(matches!(
        high.validate(0),
        Err(AraimError::OutOfRange { field: "c_int_m2", max, .. }) if max == f64::from(ceiling)
    ));
}
