//! Shared by the replay_* tests: a short window of a real data pair
//! (../shared/data, read in place) through raim-gnss and the core, with
//! the same seeded fault plans as `raim replay --fault`.
#![allow(dead_code)]

use std::path::PathBuf;

use raim_core::snapshot::fde::AlarmCause;
use raim_core::{Config, Decision, Epoch, Raim, SatId};
use raim_gnss::faults::FaultPlan;
use raim_gnss::ranging::{prepare_epoch, RangingOptions};
use raim_gnss::{time, NavData, ObsData};

pub fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/data")
        .join(name)
}

/// The sigma model fitted to the geodetic receivers' residuals
/// (docs/REPLAY.md: D^2/dof 0.76-0.79 fault-free on 0759 and ESBC).
pub fn geodetic_config() -> Config {
    let mut c = Config::default();
    c.sigma_model.ura_m = 0.3;
    c.sigma_model.iono_vertical_m = 0.5;
    c.sigma_model.noise_m = 0.2;
    c
}

#[derive(Debug, Clone)]
pub struct Row {
    pub tod: String,
    pub decision: Option<Decision>,
    pub cause: Option<AlarmCause>,
    /// Exclusions in force (decision Excluded).
    pub excluded: Vec<SatId>,
    /// Exclusions made, whatever the decision (Unavailable after an
    /// exclusion keeps them; an Alarm lists the attempts).
    pub excluded_any: Vec<SatId>,
    pub faulted: Vec<SatId>,
    pub n: usize,
    /// The satellites of the epoch.
    pub in_view: Vec<SatId>,
}

/// Replay `[start, end]` (times of day) of a data pair with `faults`.
pub fn replay(
    obs: &str,
    nav: &str,
    opts: &RangingOptions,
    cfg: &Config,
    faults: &[&str],
    start: &str,
    end: &str,
) -> Vec<Row> {
    let obs = ObsData::load(&data(obs)).unwrap();
    let nav = NavData::load(&data(nav)).unwrap();
    let first = obs.epochs[0].time_gps_s;
    let (t0, t1) = (
        time::resolve(start, first).unwrap(),
        time::resolve(end, first).unwrap(),
    );
    let plan = FaultPlan {
        faults: faults
            .iter()
            .map(|f| FaultPlan::parse_cli(f, first).unwrap())
            .collect(),
        seed: 1,
    };
    let mut raim = Raim::<48>::new();
    obs.epochs
        .iter()
        .filter(|e| e.time_gps_s >= t0 - 0.5 && e.time_gps_s <= t1 + 0.5)
        .map(|e| {
            let p = prepare_epoch(&nav, e, opts, obs.approx_position_m);
            let mut sats = p.observations();
            let inj = plan.apply(e.time_gps_s, &mut sats);
            let r = raim
                .process(cfg, &Epoch::ranges(e.time_gps_s, &sats, p.reference_m))
                .ok();
            Row {
                tod: time::time_of_day(e.time_gps_s),
                decision: r.as_ref().map(|r| r.decision),
                cause: r.as_ref().and_then(|r| r.alarm_cause),
                excluded: r
                    .as_ref()
                    .filter(|r| r.decision == Decision::Excluded)
                    .map(|r| r.exclusions.iter().map(|x| x.id).collect())
                    .unwrap_or_default(),
                excluded_any: r
                    .as_ref()
                    .map(|r| r.exclusions.iter().map(|x| x.id).collect())
                    .unwrap_or_default(),
                faulted: inj.faulted.iter().map(|(id, _)| *id).collect(),
                n: sats.len(),
                in_view: sats.iter().map(|s| s.id).collect(),
            }
        })
        .collect()
}
