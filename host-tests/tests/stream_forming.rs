//! The forming's lean bootstrap position (raim-nav `bootstrap`) against
//! the solution it replaces, raim-core's f64 Gauss-Newton solution with
//! the default configuration (`raim_core::solve::solve_into`), on real
//! epochs: ESBC's RINEX (G+R+E+C+J, 30 s, 3 hours; cold from the Earth's
//! centre and from the header's position) and the GMSD7 RTCM 3 stream
//! through the host's reader (G+R, no station position). The bootstrap
//! position is only the linearisation point of the corrections: what
//! matters is that it is the same point to well under the corrections'
//! sensitivity (a metre of height moves a zenith troposphere by 0.3 mm).

mod rtcm_common;

use raim_core::solve::{solve_into, Solution};
use raim_core::{Config, Epoch, RangeObservation};
use raim_gnss::ranging::{bootstrap_pass, prepare_at, PreparedEpoch};
use raim_gnss::{NavData, ObsData, ObsEpoch};
use raim_nav::ranging::{bootstrap_position, SURFACE_BAND_M};
use raim_recv::{Decoder, Item};
use rtcm_common::esbc::{data, NAV, OBS};
use rtcm_common::{frames, gmsd7_moved_to, in_window_week, options, GMSD7};

/// The reference positions agree within this, m.
const REFERENCE_TOL_M: f64 = 1e-3;
/// The corrected ranges and rotated satellite positions at the two
/// references agree within this, m.
const CORRECTED_TOL_M: f64 = 1e-4;

/// Capacity of the solutions (raim-gnss's bootstrap capacity).
const N: usize = 64;

/// The replaced solution: raim-core's, in f64, default configuration,
/// every satellite, within the surface band.
fn core_solution(
    time_s: f64,
    sats: &[RangeObservation],
    apriori: Option<[f64; 3]>,
) -> Option<[f64; 3]> {
    if sats.len() > N || sats.len() < 4 {
        return None;
    }
    let mut mask = [false; N];
    mask.iter_mut().take(sats.len()).for_each(|m| *m = true);
    let mut out = Solution::<N>::empty();
    solve_into(
        &Config::default(),
        &Epoch::ranges(time_s, sats, apriori),
        &mask,
        &mut out,
    )
    .ok()?;
    let p = out.position_ecef_m?;
    let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
    ((r - raim_core::frames::WGS84_A_M).abs() < SURFACE_BAND_M).then_some(p)
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// What one epoch showed: (solved by both, reference difference m,
/// largest corrected difference m).
fn compare(nav: &NavData, e: &ObsEpoch, apriori: Option<[f64; 3]>) -> (bool, f64, f64) {
    let opts = options(&Config::default().sigma_model);
    let first = bootstrap_pass(nav, e, &opts, apriori).observations();
    let lean = bootstrap_position::<N>(&first, apriori);
    let core = core_solution(e.time_gps_s, &first, apriori);
    let (lean, core) = match (lean, core) {
        (Some(l), Some(c)) => (l, c),
        (None, None) => return (false, 0.0, 0.0),
        (l, c) => panic!(
            "epoch {}: {} satellites, lean {l:?}, core {c:?}",
            e.time_gps_s,
            first.len()
        ),
    };
    let (a, b): (PreparedEpoch, PreparedEpoch) = (
        prepare_at(nav, e, &opts, lean),
        prepare_at(nav, e, &opts, core),
    );
    let ids = |p: &PreparedEpoch| p.sats.iter().map(|s| s.obs.id).collect::<Vec<_>>();
    assert_eq!(
        ids(&a),
        ids(&b),
        "epoch {}: the same satellites above the mask",
        e.time_gps_s
    );
    let worst = a
        .sats
        .iter()
        .zip(&b.sats)
        .map(|(x, y)| {
            (x.obs.pseudorange_m - y.obs.pseudorange_m)
                .abs()
                .max(distance(x.obs.position_m, y.obs.position_m))
        })
        .fold(0.0, f64::max);
    (true, distance(lean, core), worst)
}

/// Epochs solved by both, and the largest differences seen.
#[derive(Default)]
struct Tally {
    solved: usize,
    worst_ref: f64,
    worst_corr: f64,
}

impl Tally {
    fn add(&mut self, (ok, r, c): (bool, f64, f64)) {
        self.solved += usize::from(ok);
        self.worst_ref = self.worst_ref.max(r);
        self.worst_corr = self.worst_corr.max(c);
    }
}

/// ESBC's RINEX (every 3rd epoch of 3 hours, every system, the stream
/// codes), cold and from the header's position, and every GMSD7 stream
/// epoch the host's reader forms: the lean bootstrap solves exactly the
/// epochs the core's solution solves, within 1 mm of it, and the corrected
/// ranges and positions at the two references agree within 1e-4 m.
///
/// Verifies: RX-FORM-COST
#[test]
fn the_lean_bootstrap_is_the_core_solution() {
    let obs = ObsData::load(&data(OBS)).unwrap();
    let nav = NavData::load(&data(NAV)).unwrap();
    let mut t = Tally::default();
    for e in obs.epochs.iter().step_by(3) {
        t.add(compare(&nav, e, None));
        t.add(compare(&nav, e, obs.approx_position_m));
    }
    let esbc = t.solved;
    // GMSD7 through the host's stream reader (its epochs as it closes them,
    // with the ephemerides it has then).
    let file = std::fs::read(GMSD7).unwrap();
    let week = in_window_week();
    let bytes = gmsd7_moved_to(&file, week);
    let mut host = raim_recv::rtcm::Rtcm3::new(week + 1);
    let mut sobs = ObsData {
        path: GMSD7.into(),
        approx_position_m: None,
        epochs: Vec::new(),
    };
    let mut snav = NavData::default();
    let mut items = Vec::new();
    for f in frames(&bytes) {
        host.push(f, &mut items);
        let mut epochs = Vec::new();
        for it in items.drain(..) {
            match it {
                Item::Epoch(e) => epochs.push(e),
                other => raim_recv::apply(other, &mut sobs, &mut snav),
            }
        }
        for e in epochs {
            t.add(compare(&snav, &e, None));
        }
    }
    println!(
        "bootstrap: {esbc} ESBC and {} GMSD7 epochs solved by both; reference within {:.3e} m, corrected ranges and positions within {:.3e} m",
        t.solved - esbc,
        t.worst_ref,
        t.worst_corr
    );
    assert!(esbc > 200 && t.solved - esbc > 80, "{esbc} {}", t.solved);
    assert!(t.worst_ref < REFERENCE_TOL_M, "{}", t.worst_ref);
    assert!(t.worst_corr < CORRECTED_TOL_M, "{}", t.worst_corr);
}
