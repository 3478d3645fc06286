//! GEOP (smartphone, G+E by default): the noisy, non-Gaussian case. With
//! the core's default (DO-229) sigma model the fault-free phone data give
//! no alarm and no exclusion; BeiDou's unexplained km-level offsets make
//! G+E+C alarm or exclude at almost every epoch (docs/REPLAY.md).

mod replay_common;

use raim_core::{Config, Decision, System};
use raim_gnss::ranging::RangingOptions;
use replay_common::replay;

const OBS: &str = "GEOP092I.24o.gz";
const NAV: &str = "CORD00ARG_R_20240920000_01D_MN.rnx.gz";

fn ge() -> RangingOptions {
    RangingOptions {
        systems: vec![System::Gps, System::Galileo],
        ..Default::default()
    }
}

#[test]
fn clean_gps_galileo_window_has_no_alarm() {
    let rows = replay(OBS, NAV, &ge(), &Config::default(), &[], "+0", "+60");
    assert_eq!(rows.len(), 61);
    for r in &rows {
        assert!(r.n >= 8, "{r:?}");
        assert_eq!(r.decision, Some(Decision::Ok), "{r:?}");
    }
}

/// Adding BeiDou: the phone's B1I ranges carry km-level offsets, so most
/// epochs alarm or exclude (more than half of this window).
#[test]
fn beidou_on_the_phone_is_inconsistent() {
    let gec = RangingOptions {
        systems: vec![System::Gps, System::Galileo, System::Beidou],
        ..Default::default()
    };
    let rows = replay(OBS, NAV, &gec, &Config::default(), &[], "+0", "+60");
    let bad = rows
        .iter()
        .filter(|r| r.decision != Some(Decision::Ok))
        .count();
    assert!(bad > rows.len() / 2, "{bad} of {}", rows.len());
}

/// A 30 m step on one GPS satellite of the phone (seeded heavy-tailed
/// noise added on top) is still excluded in most epochs of the window.
#[test]
fn step_on_the_phone_with_heavy_tailed_noise() {
    let rows = replay(
        OBS,
        NAV,
        &ge(),
        &Config::default(),
        &["step:G12:60@+10", "noise:all:t3:0.5"],
        "+10",
        "+60",
    );
    let g12 = raim_core::SatId::new(System::Gps, 12);
    let ok = rows.iter().filter(|r| r.excluded == vec![g12]).count();
    assert!(
        rows.iter()
            .all(|r| r.excluded.is_empty() || r.excluded.contains(&g12)),
        "{rows:?}"
    );
    assert!(ok * 2 > rows.len(), "{ok} of {}", rows.len());
}
