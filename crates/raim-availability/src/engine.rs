//! The availability engine (SPEC §14): per user, per epoch, the sky above
//! the mask and one call of raim-core's ARAIM monitor, the function the
//! device, `raim araim` and `raim replay --araim` call
//! ([`Monitor::linear`]: the ISM join, C_int and C_acc from the ADD's
//! error model, the all-in-view ARAIM of ADD v3.0 / SPEC §9.1).
//!
//! Satellite positions are computed once per epoch for all users (a table
//! of epochs x satellites: it grows with the time span, not with the
//! grid); users run in parallel (rayon), each streaming over its epochs
//! and keeping only its own PL lists, so memory is flat in the grid size.

use raim_core::araim::{AraimError, AraimOutput, FdeLimits, Monitor, MonitorError, Unavailable};
use raim_core::frames::{enu_rotation, geodetic_to_ecef, rotate, Geodetic};
use raim_core::LinearObservation;
use rayon::prelude::*;

use crate::run::{Airborne, Continuity, ExclusionSpec, Study, User};

/// The engine's satellite capacity (raim-core's mode masks hold 64).
pub const N_SATS: usize = 64;
/// The engine's fault-mode capacity (an epoch that needs more is
/// unavailable, `ModeCapacity`).
pub const K_MODES: usize = 2048;

type Engine = Monitor<f64, N_SATS, K_MODES>;

/// One user's epochs of one shard: what merging needs, exactly.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct UserPartial {
    /// Epochs evaluated.
    pub epochs: u32,
    /// Epochs available.
    pub available: u32,
    /// Per epoch, the VPL in force (m; +inf without a PL).
    pub vpl_m: Vec<f64>,
    /// Per epoch, the HPL (m; +inf without a PL).
    pub hpl_m: Vec<f64>,
    /// Per epoch, the EMT (m; +inf when no mode list was monitored).
    pub emt_m: Vec<f64>,
    /// The most monitored fault modes at one epoch.
    pub max_modes: u32,
    /// Epochs the core refused for the geometry (too few satellites, a
    /// singular geometry): unavailable.
    pub refused: u32,
}

/// One user's result over the whole span.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UserSummary {
    /// Epochs evaluated.
    pub epochs: u32,
    /// Epochs available.
    pub available: u32,
    /// available / epochs.
    pub availability: f64,
    /// The `PERCENTILE` percentile of the VPL (m).
    pub vpl_pct_m: f64,
    /// The `PERCENTILE` percentile of the HPL (m).
    pub hpl_pct_m: f64,
    /// The `PERCENTILE` percentile of the EMT (m).
    pub emt_pct_m: f64,
    /// The most monitored fault modes at one epoch.
    pub max_modes: u32,
    /// Epochs refused for the geometry.
    pub refused: u32,
}

/// The PL percentile reported per user.
pub const PERCENTILE: f64 = 0.995;

/// The `p` percentile of `v`: the smallest value at or above which a share
/// `p` of the values lie, i.e. sorted[ceil(p n) - 1] (a VPL that is met
/// 99.5 % of the time); NaN for an empty list. Independent of the order of
/// `v` (so of the sharding).
pub fn percentile(v: &mut [f64], p: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let k = ((p * v.len() as f64).ceil() as usize).clamp(1, v.len());
    v[k - 1]
}

impl UserPartial {
    /// Appends `other` (a later shard of the same user).
    pub fn extend(&mut self, other: &UserPartial) {
        self.epochs += other.epochs;
        self.available += other.available;
        self.vpl_m.extend_from_slice(&other.vpl_m);
        self.hpl_m.extend_from_slice(&other.hpl_m);
        self.emt_m.extend_from_slice(&other.emt_m);
        self.max_modes = self.max_modes.max(other.max_modes);
        self.refused += other.refused;
    }

    /// The summary: a function of the multiset of values only.
    pub fn summary(mut self) -> UserSummary {
        UserSummary {
            epochs: self.epochs,
            available: self.available,
            availability: if self.epochs == 0 {
                f64::NAN
            } else {
                f64::from(self.available) / f64::from(self.epochs)
            },
            vpl_pct_m: percentile(&mut self.vpl_m, PERCENTILE),
            hpl_pct_m: percentile(&mut self.hpl_m, PERCENTILE),
            emt_pct_m: percentile(&mut self.emt_m, PERCENTILE),
            max_modes: self.max_modes,
            refused: self.refused,
        }
    }
}

/// The ECEF positions of every satellite at epochs `range`, row-major
/// (epoch, satellite), by `Kepler::state` (no light time or Earth
/// rotation during transit: the geometry of an almanac study); NaN for a
/// broadcast satellite with no valid ephemeris at that epoch (not used).
pub fn sky_table(study: &Study, range: std::ops::Range<usize>) -> Vec<[f64; 3]> {
    study.epochs_gps_s[range]
        .iter()
        .flat_map(|&t| {
            study
                .sats
                .iter()
                .map(move |s| s.position_m(t).unwrap_or([f64::NAN; 3]))
        })
        .collect()
}

/// The lines of sight (ENU, unit) of the satellites at or above the mask
/// from `user_ecef_m` (with `rot` its ENU rotation), into `out`.
pub fn visible(
    study: &Study,
    positions: &[[f64; 3]],
    user_ecef_m: [f64; 3],
    rot: &nalgebra::Matrix3<f64>,
    out: &mut Vec<LinearObservation>,
) {
    out.clear();
    let sin_mask = study.mask_rad.sin();
    for (s, p) in study.sats.iter().zip(positions) {
        if !p[0].is_finite() {
            continue;
        }
        let d = [
            p[0] - user_ecef_m[0],
            p[1] - user_ecef_m[1],
            p[2] - user_ecef_m[2],
        ];
        let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let los = rotate(rot, [d[0] / r, d[1] / r, d[2] / r]);
        if los[2] >= sin_mask {
            // The core's curves (sigma_m None) unless the constellation
            // uses the Galileo E1/E5a table or MAAST for ARAIM 2's ED-259A
            // curve: then the observation's own sigma, at the elevation
            // the core would take from the row.
            let sigma_m = match study.airborne[s.id.system.index()] {
                Airborne::GpsL1l5 => None,
                Airborne::GalileoE1e5a => Some(
                    raim_core::araim::error_model::galileo_e1e5a_variance_m2(
                        raim_core::araim::error_model::elevation_from_g(&los),
                    )
                    .sqrt(),
                ),
                Airborne::Ed259aMaast => Some(
                    crate::airborne::ed259a_maast_variance_m2(
                        raim_core::araim::error_model::elevation_from_g(&los),
                    )
                    .sqrt(),
                ),
            };
            out.push(LinearObservation {
                id: s.id,
                los_enu: los,
                residual_m: 0.0,
                sigma_m,
            });
        }
    }
}

/// One user-epoch's outcome.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EpochOutcome {
    /// The service is available (the monitor's decision is `Ok`).
    pub available: bool,
    /// VPL (m), +inf without a PL.
    pub vpl_m: f64,
    /// HPL (m), +inf without a PL.
    pub hpl_m: f64,
    /// EMT (m), +inf without a monitored mode list.
    pub emt_m: f64,
    /// sigma_v,acc (m), +inf when the epoch was refused.
    pub sigma_v_acc_m: f64,
    /// Monitored fault modes.
    pub modes: u32,
    /// The core refused the geometry.
    pub refused: bool,
}

/// Runs raim-core's ARAIM monitor on one sky (zero residuals: an
/// availability study predicts the fault-free test, which passes) and
/// reads the availability, PLs, EMT and sigma_v,acc it reports.
///
/// # Errors
/// A refusal of the monitor other than the geometry's (too few
/// satellites, a rank-deficient geometry): an input the run file should
/// have refused.
pub fn evaluate(
    study: &Study,
    monitor: &mut Engine,
    obs: &[LinearObservation],
) -> Result<EpochOutcome, MonitorError> {
    monitor.set_estimator(study.estimator)?;
    let verdict = match monitor.linear(
        &study.cfg,
        &study.ism,
        &study.ism_entries[..],
        obs,
        FdeLimits::UNLIMITED,
    ) {
        Ok(v) => v,
        Err(MonitorError::Araim(
            AraimError::TooFewSatellites { .. } | AraimError::RankDeficient { .. },
        )) => {
            return Ok(EpochOutcome {
                available: false,
                vpl_m: f64::INFINITY,
                hpl_m: f64::INFINITY,
                emt_m: f64::INFINITY,
                sigma_v_acc_m: f64::INFINITY,
                modes: 0,
                refused: true,
            })
        }
        Err(e) => return Err(e),
    };
    let out = monitor.in_force();
    // The monitor's verdict judges the LPV criteria; a horizontal-only
    // level re-judges an `Unavailable` epoch by its own criteria
    // (raim-core's `AraimOutput::available_for`).
    let available = match verdict.decision {
        raim_core::Decision::Ok => true,
        raim_core::Decision::Unavailable => {
            out.detection_passed && out.available_for(study.criteria)
        }
        raim_core::Decision::Alarm | raim_core::Decision::Excluded => false,
    };
    let mut o = EpochOutcome {
        available,
        vpl_m: f64::NEG_INFINITY,
        hpl_m: f64::NEG_INFINITY,
        emt_m: f64::NEG_INFINITY,
        sigma_v_acc_m: out.sigma_v_acc_m,
        modes: out.n_monitored as u32,
        refused: false,
    };
    o.worsen(study, out);
    if study.exclusion == ExclusionSpec::None || !o.available {
        return Ok(o);
    }
    if let (ExclusionSpec::Continuity, Some(c)) = (study.exclusion, &study.continuity) {
        o.available = continuity_holds(study, c, monitor)?;
        return Ok(o);
    }
    // Availability with exclusion: every candidate exclusion of the
    // chosen kind must leave the service available (the subset's output
    // as the core's FDE would leave it); the PLs and EMT reported are the
    // worst over the all-in-view run and those subsets.
    let candidates: Vec<usize> = out
        .modes
        .iter()
        .enumerate()
        .filter(|(_, m)| m.status == raim_core::araim::ModeStatus::Monitored)
        .filter(|(_, m)| {
            let (s, c) = (m.events.sats.count_ones(), m.events.consts.count_ones());
            match study.exclusion {
                ExclusionSpec::None | ExclusionSpec::Continuity => false,
                ExclusionSpec::Satellites => s == 1 && c == 0,
                ExclusionSpec::SingleEvents => s + c == 1,
            }
        })
        .map(|(k, _)| k)
        .collect();
    for k in candidates {
        match monitor.after_excluding(&study.cfg, &study.ism, k)? {
            Some(sub) => {
                o.available &= sub.available_for(study.criteria);
                o.worsen(study, sub);
            }
            None => {
                o.available = false;
                o.vpl_m = f64::INFINITY;
                o.hpl_m = f64::INFINITY;
            }
        }
    }
    Ok(o)
}

/// The probability that fault mode `events` starts within the exposure
/// `c.t_exp_s`: for one event e, R_e T_exp = P_e T_exp / MFD_e (the fault
/// rate of ADD v4.x, P over the mean fault duration); for several, the
/// bound sum_e R_e T_exp prod_{f != e} P_f = p_k sum_e T_exp / MFD_e (one
/// event starts while the others are present), p_k the mode's prior
/// (which for a merged mode is above the product, so the bound holds).
pub fn onset_probability(
    c: &Continuity,
    events: &raim_core::araim::ModeEvents,
    sats: &[raim_core::araim::AraimSat<f64>],
) -> f64 {
    let mut per_s = 0.0;
    for (i, s) in sats.iter().enumerate().take(64) {
        if events.sats >> i & 1 == 1 {
            per_s += 1.0 / c.mfd_sat_s[s.id.system.index()];
        }
    }
    for (j, sys) in raim_core::System::ALL.iter().enumerate() {
        if events.consts >> j & 1 == 1 {
            per_s += 1.0 / c.mfd_const_s[sys.index()];
        }
    }
    events.prior * c.t_exp_s * per_s
}

/// `exclusion = "continuity"` (docs/AVAILABILITY.md "Availability with
/// exclusion"), after an available all-in-view epoch: the monitored fault
/// modes whose exclusion leaves the service unavailable (the subset's
/// output as raim-core's FDE leaves it, [`Monitor::after_excluding`]; a
/// subset the core cannot solve counts as unavailable) must start within
/// the exposure with a summed probability at most `c.p_alloc`. Candidates
/// are taken by decreasing onset probability; the search stops once the
/// failures exceed the allocation (unavailable) or once the candidates
/// left could not exceed it even if all failed (available), so the
/// decision is the one every candidate evaluated would give.
///
/// # Errors
/// As [`evaluate`].
pub fn continuity_holds(
    study: &Study,
    c: &Continuity,
    monitor: &mut Engine,
) -> Result<bool, MonitorError> {
    let out = monitor.all_in_view();
    let sats = monitor.satellites();
    let mut cands: Vec<(usize, f64)> = out
        .modes
        .iter()
        .enumerate()
        .filter(|(_, m)| m.status == raim_core::araim::ModeStatus::Monitored)
        .map(|(k, m)| (k, onset_probability(c, &m.events, sats)))
        .collect();
    cands.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    // left[i]: the onset probability of candidates i.. (summed from the
    // smallest, so that it is exact to rounding and never below the sum).
    let mut left = vec![0.0; cands.len() + 1];
    for i in (0..cands.len()).rev() {
        left[i] = left[i + 1] + cands[i].1;
    }
    let mut failed = 0.0;
    for (i, &(k, w)) in cands.iter().enumerate() {
        if failed + left[i] <= c.p_alloc {
            return Ok(true);
        }
        let ok = monitor
            .after_excluding(&study.cfg, &study.ism, k)?
            .is_some_and(|sub| sub.available_for(study.criteria));
        if !ok {
            failed += w;
            if failed > c.p_alloc {
                return Ok(false);
            }
        }
    }
    Ok(true)
}

impl EpochOutcome {
    /// Takes the larger of each reported level and `out`'s (the PL the
    /// configuration judges; the EMT +inf when no mode was monitored).
    fn worsen<const K: usize>(&mut self, study: &Study, out: &AraimOutput<f64, K>) {
        let pl = match study.cfg.pl_output {
            raim_core::araim::PlOutput::AddBracket => out.pl_add,
            raim_core::araim::PlOutput::Exact => out.pl_exact,
        };
        let monitored = !matches!(
            out.unavailable,
            Some(Unavailable::ModeCapacity { .. } | Unavailable::TooManyEvents { .. })
        );
        let emt = if monitored { out.emt_m } else { f64::INFINITY };
        self.vpl_m = self.vpl_m.max(pl.vpl_m);
        self.hpl_m = self.hpl_m.max(pl.hpl_m);
        self.emt_m = self.emt_m.max(emt);
    }
}

/// A fresh engine on the heap (two ARAIM engines of `K_MODES` modes).
pub fn new_engine() -> Box<Engine> {
    Box::new(Monitor::new())
}

/// The ECEF position and ENU rotation of a user at the study's height.
pub fn user_frame(study: &Study, u: &User) -> ([f64; 3], nalgebra::Matrix3<f64>) {
    let g = Geodetic {
        lat_rad: u.lat_deg.to_radians(),
        lon_rad: u.lon_deg.to_radians(),
        height_m: study.height_m,
    };
    (geodetic_to_ecef(g), enu_rotation(&g))
}

/// One user over the epochs whose positions are `sky` (rows of
/// `study.sats.len()`).
///
/// # Errors
/// As [`evaluate`].
pub fn run_user(
    study: &Study,
    sky: &[[f64; 3]],
    u: &User,
    monitor: &mut Engine,
    obs: &mut Vec<LinearObservation>,
) -> Result<UserPartial, MonitorError> {
    let (x, rot) = user_frame(study, u);
    let n = study.sats.len();
    let epochs = sky.len() / n.max(1);
    let mut p = UserPartial {
        vpl_m: Vec::with_capacity(epochs),
        hpl_m: Vec::with_capacity(epochs),
        emt_m: Vec::with_capacity(epochs),
        ..UserPartial::default()
    };
    for row in sky.chunks_exact(n) {
        visible(study, row, x, &rot, obs);
        let o = evaluate(study, monitor, obs)?;
        p.epochs += 1;
        p.available += u32::from(o.available);
        p.vpl_m.push(o.vpl_m);
        p.hpl_m.push(o.hpl_m);
        p.emt_m.push(o.emt_m);
        p.max_modes = p.max_modes.max(o.modes);
        p.refused += u32::from(o.refused);
    }
    Ok(p)
}

/// Every user over epochs `range`, in parallel over users, in user order.
/// `finish` maps each user's partial to what is kept (the summary for a
/// whole run, the partial itself for a shard), so that a whole run holds
/// one user's PL lists per thread at a time.
///
/// # Errors
/// The first user's [`evaluate`] error.
pub fn run_users<R: Send>(
    study: &Study,
    range: std::ops::Range<usize>,
    finish: impl Fn(UserPartial) -> R + Sync,
) -> Result<Vec<R>, MonitorError> {
    let sky = sky_table(study, range);
    // A progress bar on stderr, drawn only when stderr is a terminal.
    let bar = indicatif::ProgressBar::new(study.users.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} users, {eta} left")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let out = study
        .users
        .par_iter()
        .map_init(
            || (new_engine(), Vec::with_capacity(N_SATS)),
            |(m, obs), u| {
                let r = run_user(study, &sky, u, m, obs).map(&finish);
                bar.inc(1);
                r
            },
        )
        .collect();
    bar.finish_and_clear();
    out
}

/// The worker threads' stack: the monitor is built on the stack before it
/// is boxed, and `Araim::process` forms its output there
/// (docs/ARAIM.md "Not done": about 170 B per mode).
pub const STACK_BYTES: usize = 4 * std::mem::size_of::<Engine>() + (16 << 20);

#[cfg(test)]
#[path = "engine_adjusted_tests.rs"]
mod adjusted_tests;
