//! The TOML run file of an availability study (docs/AVAILABILITY.md "Run
//! file"): the constellations with their almanacs, outages and ISM, the
//! user grid, the time span, the mask and the service level. Every number
//! is named with its unit; errors name the file and line.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{anyhow, bail, Result};
use raim_core::araim::{AraimConfig, Criteria, Estimator, Ism, SatIsm};
use raim_core::{SatId, System};
use serde::Deserialize;

use crate::almanac::{self, AlmanacSpec};

/// The run file as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunFile {
    /// The scenario's name: the output files' stem and the maps' title.
    pub name: String,
    /// The elevation mask (degrees).
    pub mask_deg: f64,
    /// Every user's height above the WGS-84 ellipsoid (m).
    #[serde(default)]
    pub height_m: f64,
    /// Availability with exclusion: `none` (detection only, the default),
    /// `continuity` (the fault modes whose exclusion would leave the
    /// service unavailable must start within the exposure with a summed
    /// probability inside the continuity allocation to failed exclusions,
    /// `[continuity]`), or the strict rules `satellites` (every
    /// single-satellite exclusion must leave the service available) and
    /// `single_events` (satellites and whole constellations).
    #[serde(default)]
    pub exclusion: ExclusionSpec,
    /// The continuity allocation of `exclusion = "continuity"`.
    pub continuity: Option<ContinuitySpec>,
    /// The all-in-view position estimator: `all_in_view` (SPEC §9.1's
    /// weighted least squares, the default) or `adjusted` (Blanch et al.
    /// 2015, raim-core `araim::adjusted`; docs/AVAILABILITY.md "The
    /// adjusted position estimator").
    #[serde(default)]
    pub position: PositionSpec,
    /// `position = "adjusted"`: the accuracy limits it may spend per axis
    /// E, N, U (m); by default the service level's sigma_acc limit on
    /// every axis.
    pub adjusted_sigma_acc_max_m: Option<[f64; 3]>,
    /// The time span.
    pub time: TimeSpec,
    /// The users.
    pub grid: GridSpec,
    /// The service level.
    pub service: ServiceSpec,
    /// One entry per constellation.
    pub constellation: Vec<ConstellationSpec>,
    /// A sweep: scenarios, each the run with what it names overridden
    /// (read by `crate::sweep`; docs/AVAILABILITY.md "Sweeps").
    #[serde(default)]
    pub scenario: Vec<toml::Table>,
}

/// The all-in-view position estimator (`position`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PositionSpec {
    /// The weighted least squares of SPEC §9.1 step 2.
    #[default]
    AllInView,
    /// The adjusted estimator of Blanch et al. 2015 (raim-core
    /// `araim::adjusted`).
    Adjusted,
}

/// Which exclusions must leave the service available (docs/AVAILABILITY.md
/// "Availability with exclusion").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ExclusionSpec {
    /// Detection only.
    #[default]
    None,
    /// Each monitored single-satellite mode.
    Satellites,
    /// Each monitored single-event mode: satellites and constellations.
    SingleEvents,
    /// The failed exclusions' onset probability within the continuity
    /// allocation (docs/AVAILABILITY.md "Availability with exclusion").
    Continuity,
}

/// An almanac file's format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AlmanacFormat {
    /// YUMA (`almanac::parse`).
    #[default]
    Yuma,
    /// SEM (`almanac::parse_sem`).
    Sem,
}

/// A constellation's airborne multipath and noise curve.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Airborne {
    /// The ADD's GPS L1/L5 curves (raim-core's `Curves::default()`).
    #[default]
    GpsL1l5,
    /// The Galileo E1/E5a table (raim-core's `galileo_e1e5a_variance_m2`).
    GalileoE1e5a,
    /// The dual-frequency curve MAAST for ARAIM 2 implements after ED-259A
    /// (`airborne::ed259a_maast_variance_m2`), for GPS and Galileo alike.
    Ed259aMaast,
}

/// The continuity allocation to failed exclusions (`[continuity]`).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContinuitySpec {
    /// P_ALERT: the continuity budget for disruptions by false alerts and
    /// failed exclusions, per exposure; the false-alert share P_FA,V +
    /// P_FA,H of the service level is taken out of it.
    pub p_alert: f64,
    /// The exposure time over which a fault may start (s).
    pub t_exp_s: f64,
}

/// The continuity rule as the engine applies it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Continuity {
    /// The allocation to failed exclusions: P_ALERT - P_FA,V - P_FA,H.
    pub p_alloc: f64,
    /// The exposure time (s).
    pub t_exp_s: f64,
    /// Per system (`System::index()`), the mean fault duration of a
    /// satellite fault (s); NaN for a system not in the study.
    pub mfd_sat_s: [f64; raim_core::measurement::MAX_SYSTEMS],
    /// Per system, the mean fault duration of a constellation fault (s).
    pub mfd_const_s: [f64; raim_core::measurement::MAX_SYSTEMS],
}

/// Epochs `start_s + k step_s` for `k` in `0..floor(span_s / step_s)` (the
/// end excluded: 24 h at 300 s is 288 epochs).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeSpec {
    /// Seconds from the start of the first almanac's GPS week.
    pub start_s: f64,
    /// The span (s).
    pub span_s: f64,
    /// The step (s).
    pub step_s: f64,
}

/// The users: a world grid, a region or a list of sites.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, tag = "kind", rename_all = "lowercase")]
pub enum GridSpec {
    /// Latitudes -90..=90 and longitudes -180..<180 at `step_deg`.
    World {
        /// Grid step (degrees).
        step_deg: f64,
    },
    /// Latitudes `lat_min_deg..=lat_max_deg` and longitudes
    /// `lon_min_deg..=lon_max_deg` at `step_deg`.
    Region {
        /// Grid step (degrees).
        step_deg: f64,
        /// Southern edge (degrees).
        lat_min_deg: f64,
        /// Northern edge (degrees).
        lat_max_deg: f64,
        /// Western edge (degrees).
        lon_min_deg: f64,
        /// Eastern edge (degrees).
        lon_max_deg: f64,
    },
    /// Named sites (airports), each weighted by cos(latitude) too.
    Sites {
        /// The sites.
        sites: Vec<Site>,
    },
}

/// One named user position.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Site {
    /// Its name (for the CSV).
    pub name: String,
    /// Latitude (degrees).
    pub lat_deg: f64,
    /// Longitude (degrees).
    pub lon_deg: f64,
}

/// The service level: a preset or the limits given.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ServiceSpec {
    /// `LPV-200`, `LPV-250` or `custom`.
    pub level: String,
    /// The availability target (0.995 for LPV-200).
    #[serde(default = "default_target")]
    pub target: f64,
    /// Custom: the VAL (m).
    pub val_m: Option<f64>,
    /// Custom: the HAL (m).
    pub hal_m: Option<f64>,
    /// Custom: the EMT limit (m).
    pub emt_max_m: Option<f64>,
    /// Custom: the sigma_v,acc limit (m).
    pub sigma_acc_max_m: Option<f64>,
    /// Horizontal-only levels (required there, refused elsewhere): the
    /// level's whole integrity budget, a probability per epoch (per
    /// independent sample, as raim-core applies SPEC §9.1's PHMI at every
    /// epoch). All of it goes to the horizontal: raim-core's PHMI_VERT at
    /// its floor (`config_bounds::araim::PHMI_VERT.min`, the VPL is not
    /// judged) and PHMI_HOR the rest, so that PHMI_VERT + PHMI_HOR equals
    /// it and the HMI risk, P_unmon included, stays within it.
    pub phmi: Option<f64>,
    /// Horizontal-only levels (required there): the level's whole
    /// false-alert budget, a probability per epoch, split as `phmi`
    /// (P_FA_VERT at its floor, P_FA_HOR the rest).
    pub p_fa: Option<f64>,
}

fn default_target() -> f64 {
    0.995
}

/// One constellation: its almanac, outages and ISM.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConstellationSpec {
    /// `G` or `E`.
    pub system: String,
    /// The almanac file, relative to the run file's directory (or
    /// `navigation`).
    pub almanac: Option<PathBuf>,
    /// A RINEX navigation file (2 or 3, gzip or not), relative to the run
    /// file's directory: the constellation's broadcast ephemerides, at
    /// each epoch the healthy set nearest in toe within its validity
    /// window (or `almanac`).
    pub navigation: Option<PathBuf>,
    /// Its format: `yuma` (the default) or `sem` (GPS SEM, USCG NAVCEN).
    #[serde(default)]
    pub format: AlmanacFormat,
    /// A second almanac (same format, week and ID rules) from which the
    /// satellites `add` are taken.
    pub add_almanac: Option<PathBuf>,
    /// PRNs added from `add_almanac` (a satellite not in `almanac`, or
    /// one taken out by `remove` and replaced).
    #[serde(default)]
    pub add: Vec<u8>,
    /// 1024-week rollovers to add to the file's 10-bit week.
    pub week_rollovers: Option<u32>,
    /// PRN = almanac ID - `id_offset`.
    #[serde(default)]
    pub id_offset: u32,
    /// PRNs taken out (outages).
    #[serde(default)]
    pub remove: Vec<u8>,
    /// sigma_URA (m).
    pub sigma_ura_m: f64,
    /// sigma_URE (m).
    pub sigma_ure_m: f64,
    /// b_nom (m).
    pub b_nom_m: f64,
    /// P_sat.
    pub p_sat: f64,
    /// P_const.
    pub p_const: f64,
    /// The airborne multipath and noise curve: `gps_l1l5` (the ADD's GPS
    /// L1/L5 curves through the iono-free factor, raim-core's default, the
    /// default here), `galileo_e1e5a` (the Galileo E1/E5a table MAAST's
    /// ARAIM uses, raim-core's `error_model::galileo_e1e5a_sigma_m`) or
    /// `ed259a_maast` (MAAST for ARAIM 2's ED-259A curve with its
    /// ionospheric residual, `airborne::ed259a_maast_variance_m2`).
    #[serde(default)]
    pub airborne: Airborne,
    /// Mean duration of a satellite fault (s; `exclusion = "continuity"`).
    pub mfd_sat_s: Option<f64>,
    /// Mean duration of a constellation fault (s; `exclusion =
    /// "continuity"`).
    pub mfd_const_s: Option<f64>,
}

/// A satellite's orbit.
#[derive(Debug, Clone)]
pub enum Orbit {
    /// One almanac record (every harmonic correction zero, toe its time of
    /// applicability).
    Almanac(raim_nav::ephemeris::Kepler),
    /// The broadcast ephemerides of a RINEX navigation file, read by
    /// raim-gnss's `NavData` (the replay's reader): at each epoch the
    /// healthy set whose toe is nearest, within the system's validity
    /// window (`NavData::select`, the replay's selection); none outside it.
    Broadcast(Arc<raim_gnss::NavData>),
}

/// One satellite of the study.
#[derive(Debug, Clone)]
pub struct StudySat {
    /// The satellite.
    pub id: SatId,
    /// Its orbit.
    pub orbit: Orbit,
}

impl StudySat {
    /// The Keplerian set in force at `t_gps_s`: the almanac record, or the
    /// selected broadcast ephemeris (None: no healthy set valid then, the
    /// satellite is not used at that epoch).
    pub fn kepler_at(&self, t_gps_s: f64) -> Option<&raim_nav::ephemeris::Kepler> {
        match &self.orbit {
            Orbit::Almanac(k) => Some(k),
            Orbit::Broadcast(nav) => nav.select(self.id, t_gps_s),
        }
    }

    /// The ECEF position at `t_gps_s` by `Kepler::state` (IS-GPS-200's
    /// equations, the receiver's), or None without a valid set.
    pub fn position_m(&self, t_gps_s: f64) -> Option<[f64; 3]> {
        self.kepler_at(t_gps_s).map(|k| k.state(t_gps_s).position_m)
    }

    /// True for a broadcast (RINEX) orbit.
    pub fn is_broadcast(&self) -> bool {
        matches!(self.orbit, Orbit::Broadcast(_))
    }
}

/// One user of the grid.
#[derive(Debug, Clone, PartialEq)]
pub struct User {
    /// A site's name; empty on a grid.
    pub name: String,
    /// Latitude (degrees, as given).
    pub lat_deg: f64,
    /// Longitude (degrees, as given).
    pub lon_deg: f64,
    /// The area weight cos(latitude).
    pub weight: f64,
}

/// A run file read and checked: everything the engine needs.
#[derive(Debug, Clone)]
pub struct Study {
    /// The scenario's name.
    pub name: String,
    /// The satellites in use, constellation by constellation, in PRN order.
    pub sats: Vec<StudySat>,
    /// Their ISM entries (same order).
    pub ism_entries: Vec<SatIsm>,
    /// P_const per constellation.
    pub ism: Ism,
    /// The ARAIM configuration (the service level's limits).
    pub cfg: AraimConfig,
    /// The criteria the service level judges: LPV's four limits, or the
    /// HAL alone (H-ARAIM).
    pub criteria: Criteria,
    /// A horizontal-only level's own budgets as the run file gives them
    /// (`phmi`, `p_fa`, per epoch), already in `cfg`
    /// ([`horizontal_budgets`]); `None` for the LPV levels.
    pub budgets: Option<[f64; 2]>,
    /// The availability target.
    pub target: f64,
    /// Which exclusions must leave the service available.
    pub exclusion: ExclusionSpec,
    /// The continuity rule (`exclusion = "continuity"` only).
    pub continuity: Option<Continuity>,
    /// The all-in-view position estimator (`position`).
    pub estimator: Estimator,
    /// Per system (`System::index()`), the airborne curve.
    pub airborne: [Airborne; raim_core::measurement::MAX_SYSTEMS],
    /// The elevation mask (rad).
    pub mask_rad: f64,
    /// The users' height (m).
    pub height_m: f64,
    /// The users.
    pub users: Vec<User>,
    /// The epochs, GPS seconds since 1980-01-06.
    pub epochs_gps_s: Vec<f64>,
    /// The unhealthy satellites left out, per constellation letter.
    pub unhealthy: Vec<String>,
    /// The run file's text: the partial results carry its digest.
    pub source: String,
}

/// Where a run file's keys are, for errors about a value the TOML parser
/// accepted: the file's name, its text, and the lines (0-based, end
/// excluded) searched first: the part before the first `[[scenario]]` for
/// the run as written, a scenario's own lines for a scenario
/// (`crate::sweep`), then the whole file.
#[derive(Debug, Clone)]
pub struct Loc<'a> {
    /// The file's name as given.
    pub file: String,
    text: &'a str,
    lines: std::ops::Range<usize>,
}

impl<'a> Loc<'a> {
    /// The run as written: the lines before the first `[[scenario]]`.
    pub fn base(text: &'a str, path: &Path) -> Loc<'a> {
        let end = text
            .lines()
            .position(|l| l.trim() == "[[scenario]]")
            .unwrap_or(usize::MAX);
        Loc {
            file: path.display().to_string(),
            text,
            lines: 0..end,
        }
    }

    /// A scenario's lines `lines` (0-based, end excluded).
    pub fn within(text: &'a str, path: &Path, lines: std::ops::Range<usize>) -> Loc<'a> {
        Loc {
            file: path.display().to_string(),
            text,
            lines,
        }
    }

    /// The whole file's text.
    pub fn text(&self) -> &'a str {
        self.text
    }

    /// The 1-based line of the first line satisfying `pred`, in this
    /// location's lines first, then anywhere (0 when none).
    pub fn line_where(&self, pred: impl Fn(&str) -> bool) -> usize {
        let found = |r: std::ops::Range<usize>| {
            self.text
                .lines()
                .enumerate()
                .skip(r.start)
                .take(r.end.saturating_sub(r.start))
                .find(|(_, l)| pred(l))
                .map(|(i, _)| i + 1)
        };
        found(self.lines.clone())
            .or_else(|| found(0..usize::MAX))
            .unwrap_or(0)
    }

    /// The 1-based line of the first line that starts with `key =`, or
    /// opens table `key` (`[key]`, `[scenario.key]`, or as an array).
    pub fn line_of(&self, key: &str) -> usize {
        self.line_where(|l| {
            let t = l.trim();
            let header = t.trim_start_matches('[').trim_end_matches(']');
            t.starts_with('[') && (header == key || header.strip_prefix("scenario.") == Some(key))
                || t.strip_prefix(key)
                    .is_some_and(|r| r.trim_start().starts_with('='))
        })
    }

    /// `file:line` of `key`.
    pub fn at(&self, key: &str) -> String {
        format!("{}:{}", self.file, self.line_of(key))
    }
}

/// Reads and checks the run file at `path` (the run as written: its
/// `[[scenario]]` list, if any, is `crate::sweep`'s).
///
/// # Errors
/// TOML errors (with the parser's line and column), an unknown level or
/// system, a bad grid or time span, an ISM or service level that raim-core's
/// bounds refuse, an outage PRN not in the almanac, an almanac error, a
/// span more than half a week from an almanac's time of applicability.
pub fn load(path: &Path) -> Result<Study> {
    let text = std::fs::read_to_string(path).map_err(|e| anyhow!("{}: {e}", path.display()))?;
    let base = path.parent().unwrap_or(Path::new("."));
    from_text(&text, path, base)
}

/// [`load`] on text in memory; `path` names it in errors, almanac paths
/// are relative to `base`.
///
/// # Errors
/// As [`load`].
pub fn from_text(text: &str, path: &Path, base: &Path) -> Result<Study> {
    let run = parse(text, path)?;
    build(&run, &Loc::base(text, path), base)
}

/// Parses the run file's text (TOML errors with the parser's line).
///
/// # Errors
/// A TOML or schema error.
pub fn parse<T: serde::de::DeserializeOwned>(text: &str, path: &Path) -> Result<T> {
    let file = path.display();
    toml::from_str(text).map_err(|e| {
        let line = e
            .span()
            .map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1);
        match line {
            Some(l) => anyhow!("{file}:{l}: {}", e.message()),
            None => anyhow!("{file}: {}", e.message()),
        }
    })
}

/// A horizontal-only level's own budgets into raim-core's allocation:
/// the vertical integrity and false-alert budgets at the core's floors
/// (`config_bounds::araim::PHMI_VERT.min`, `PFA_VERT.min`: the VPL is
/// computed but not judged), the horizontal ones the rest, so that
/// PHMI_VERT + PHMI_HOR = `phmi` and P_FA_VERT + P_FA_HOR = `p_fa`. The
/// core's PL equations (SPEC §9.1 steps 4-6) then bound the HMI risk by
/// PHMI_HOR (1 - P_unmon / `phmi`) + P_unmon <= `phmi`, and its K_fa
/// spends `p_fa` (the vertical share at the floor included). The core's
/// bounds and cross-field rules (`AraimConfig::validate`, run by the
/// caller) then apply: P_THRES below `phmi`, each share within its range.
///
/// # Errors
/// A budget that is not a probability above twice the core's floor (one
/// floor for each axis).
pub fn horizontal_budgets(cfg: &mut AraimConfig, phmi: f64, p_fa: f64) -> Result<()> {
    use raim_core::config_bounds::araim::{PFA_VERT, PHMI_VERT};
    for (name, v, floor) in [("phmi", phmi, PHMI_VERT.min), ("p_fa", p_fa, PFA_VERT.min)] {
        if !(v.is_finite() && v > 2.0 * floor && v < 1.0) {
            bail!("{name} {v} outside ({}, 1): a probability per epoch above twice raim-core's floor {floor} (one share per axis)", 2.0 * floor);
        }
    }
    cfg.phmi_vert = PHMI_VERT.min;
    cfg.phmi_hor = phmi - PHMI_VERT.min;
    cfg.pfa_vert = PFA_VERT.min;
    cfg.pfa_hor = p_fa - PFA_VERT.min;
    Ok(())
}

/// Checks a run (as written, or a scenario of it merged by
/// `crate::sweep`) and forms its study; errors name `loc`'s file and
/// lines; almanac paths are relative to `base`.
///
/// # Errors
/// As [`load`].
pub fn build(run: &RunFile, loc: &Loc<'_>, base: &Path) -> Result<Study> {
    let file = &loc.file;
    let at = |key: &str| loc.at(key);
    if !(0.0..90.0).contains(&run.mask_deg) {
        bail!(
            "{}: mask_deg {} outside [0, 90)",
            at("mask_deg"),
            run.mask_deg
        );
    }
    if !(-1000.0..=100_000.0).contains(&run.height_m) {
        bail!(
            "{}: height_m {} outside [-1000, 100000]",
            at("height_m"),
            run.height_m
        );
    }
    // Service level.
    let mut cfg = AraimConfig::default();
    let mut criteria = Criteria::Vertical;
    let level = run.service.level.as_str();
    // H-ARAIM levels: the HAL alone, the RAIM alert limits of en route
    // (2 NM), terminal (1 NM) and non-precision approach (0.3 NM); the
    // vertical limits keep their defaults and are not judged.
    let horizontal = match level {
        "H-ARAIM-en-route" => Some(Some(3704.0)),
        "H-ARAIM-terminal" => Some(Some(1852.0)),
        "H-ARAIM-NPA" => Some(Some(555.6)),
        "custom-horizontal" => Some(None),
        _ => None,
    };
    match level {
        _ if horizontal.is_some() => {
            criteria = Criteria::HorizontalOnly;
            if [
                run.service.val_m,
                run.service.emt_max_m,
                run.service.sigma_acc_max_m,
            ]
            .iter()
            .any(Option::is_some)
            {
                bail!(
                    "{}: level `{level}` judges the HAL alone: no val_m, emt_max_m or sigma_acc_max_m",
                    at("level")
                );
            }
            cfg.hal_m = match (horizontal.flatten(), run.service.hal_m) {
                (Some(h), None) => h,
                (None, Some(h)) => h,
                (None, None) => bail!("{}: level = \"custom-horizontal\" needs `hal_m`", at("level")),
                (Some(_), Some(_)) => bail!("{}: level `{level}` sets its HAL; hal_m is given only with \"custom-horizontal\"", at("level")),
            };
            let (Some(phmi), Some(p_fa)) = (run.service.phmi, run.service.p_fa) else {
                bail!(
                    "{}: level `{level}` needs its own budgets `phmi` and `p_fa` (probabilities per epoch; docs/AVAILABILITY.md \"Service levels\")",
                    at("level")
                );
            };
            horizontal_budgets(&mut cfg, phmi, p_fa)
                .map_err(|e| anyhow!("{}: {e}", at("phmi")))?;
        }
        "LPV-200" => {}
        "LPV-250" => cfg.val_m = 50.0,
        "custom" => {
            let need = |v: Option<f64>, k: &str| {
                v.ok_or_else(|| anyhow!("{}: level = \"custom\" needs `{k}`", at("level")))
            };
            cfg.val_m = need(run.service.val_m, "val_m")?;
            cfg.hal_m = need(run.service.hal_m, "hal_m")?;
            cfg.emt_max_m = need(run.service.emt_max_m, "emt_max_m")?;
            cfg.sigma_acc_max_m = need(run.service.sigma_acc_max_m, "sigma_acc_max_m")?;
        }
        other => bail!(
            "{}: unknown service level `{other}` (LPV-200, LPV-250, custom, H-ARAIM-en-route, H-ARAIM-terminal, H-ARAIM-NPA or custom-horizontal)",
            at("level")
        ),
    }
    if horizontal.is_none() && (run.service.phmi.is_some() || run.service.p_fa.is_some()) {
        bail!(
            "{}: `phmi` and `p_fa` are given only with a horizontal-only level (the LPV levels use SPEC §9.1's budgets)",
            at("level")
        );
    }
    if run.service.level != "custom"
        && horizontal.is_none()
        && [
            run.service.val_m,
            run.service.hal_m,
            run.service.emt_max_m,
            run.service.sigma_acc_max_m,
        ]
        .iter()
        .any(Option::is_some)
    {
        bail!(
            "{}: limits are given only with level = \"custom\"",
            at("level")
        );
    }
    let estimator = match (run.position, run.adjusted_sigma_acc_max_m) {
        (PositionSpec::AllInView, None) => Estimator::AllInView,
        (PositionSpec::AllInView, Some(_)) => bail!(
            "{}: adjusted_sigma_acc_max_m is read only with position = \"adjusted\"",
            at("adjusted_sigma_acc_max_m")
        ),
        (PositionSpec::Adjusted, limits) => Estimator::Adjusted {
            sigma_acc_max_m: limits.unwrap_or([cfg.sigma_acc_max_m; 3]),
        },
    };
    estimator
        .validate()
        .map_err(|e| anyhow!("{}: {e}", at("adjusted_sigma_acc_max_m")))?;
    cfg.validate().map_err(|e| {
        anyhow!(
            "{}: the service level is refused by raim-core: {e}",
            at("level")
        )
    })?;
    let target = run.service.target;
    if !(target > 0.0 && target <= 1.0) {
        bail!("{}: target {target} outside (0, 1]", at("target"));
    }
    // Time.
    let t = run.time;
    let finite = t.step_s.is_finite() && t.span_s.is_finite() && t.start_s.is_finite();
    if !finite || t.step_s <= 0.0 || t.span_s < t.step_s {
        bail!(
            "{}: the time span needs 0 < step_s <= span_s, finite (start_s {}, span_s {}, step_s {})",
            at("step_s"),
            t.start_s,
            t.span_s,
            t.step_s
        );
    }
    let n_epochs = (t.span_s / t.step_s).floor() as usize;
    if n_epochs > 10_000_000 {
        bail!("{}: {n_epochs} epochs: more than 10^7", at("span_s"));
    }
    // Users.
    let users = users(&run.grid).map_err(|e| anyhow!("{}: {e}", at("kind")))?;
    if users.is_empty() {
        bail!("{}: the grid has no user", at("kind"));
    }
    // Constellations.
    if run.constellation.is_empty() {
        bail!("{file}: no [[constellation]]");
    }
    let mut ism = Ism::default();
    let mut sats = Vec::new();
    let mut entries = Vec::new();
    let mut unhealthy = Vec::new();
    let mut week0: Option<u32> = None;
    let mut almanac_sats = Vec::new();
    let mut navs: BTreeMap<PathBuf, Arc<raim_gnss::NavData>> = BTreeMap::new();
    let continuous = run.exclusion == ExclusionSpec::Continuity;
    let mut continuity = match (continuous, run.continuity) {
        (true, Some(c)) => {
            let p_alloc = c.p_alert - (cfg.pfa_vert + cfg.pfa_hor);
            if !(c.p_alert.is_finite() && p_alloc > 0.0 && c.p_alert < 1.0) {
                bail!(
                    "{}: p_alert {} must exceed the false-alert budget P_FA,V + P_FA,H = {} and be below 1",
                    at("p_alert"),
                    c.p_alert,
                    cfg.pfa_vert + cfg.pfa_hor
                );
            }
            if !(c.t_exp_s.is_finite() && c.t_exp_s > 0.0) {
                bail!("{}: t_exp_s {} must be positive", at("t_exp_s"), c.t_exp_s);
            }
            Some(Continuity {
                p_alloc,
                t_exp_s: c.t_exp_s,
                mfd_sat_s: [f64::NAN; raim_core::measurement::MAX_SYSTEMS],
                mfd_const_s: [f64::NAN; raim_core::measurement::MAX_SYSTEMS],
            })
        }
        (true, None) => bail!(
            "{}: exclusion = \"continuity\" needs a [continuity] table (p_alert, t_exp_s)",
            at("exclusion")
        ),
        (false, Some(_)) => bail!(
            "{file}:{}: [continuity] is read only with exclusion = \"continuity\"",
            loc.line_where(|l| matches!(l.trim(), "[continuity]" | "[scenario.continuity]"))
        ),
        (false, None) => None,
    };
    let mut airborne = [Airborne::GpsL1l5; raim_core::measurement::MAX_SYSTEMS];
    for (ci, c) in run.constellation.iter().enumerate() {
        let here = format!(
            "{file}: [[constellation]] {} (system {:?})",
            ci + 1,
            c.system
        );
        let system = match c.system.as_str() {
            "G" => System::Gps,
            "E" => System::Galileo,
            s => bail!("{here}: system `{s}`: G or E (the almanac forms read here)"),
        };
        if ism.p_const[system.index()].is_some() {
            bail!("{here}: the constellation is given twice");
        }
        ism.p_const[system.index()] = Some(c.p_const);
        airborne[system.index()] = c.airborne;
        if c.airborne == Airborne::GalileoE1e5a && run.mask_deg < 5.0 {
            bail!(
                "{here}: airborne = \"galileo_e1e5a\" needs mask_deg >= 5 (the table starts at 5 deg; mask_deg {})",
                run.mask_deg
            );
        }
        match (&mut continuity, c.mfd_sat_s, c.mfd_const_s) {
            (Some(k), Some(s), Some(cst)) => {
                for (v, name) in [(s, "mfd_sat_s"), (cst, "mfd_const_s")] {
                    if !(v.is_finite() && v > 0.0) {
                        bail!("{here}: {name} {v} must be positive");
                    }
                }
                k.mfd_sat_s[system.index()] = s;
                k.mfd_const_s[system.index()] = cst;
            }
            (Some(_), _, _) => {
                bail!("{here}: exclusion = \"continuity\" needs mfd_sat_s and mfd_const_s")
            }
            (None, None, None) => {}
            (None, _, _) => bail!(
                "{here}: mfd_sat_s and mfd_const_s are read only with exclusion = \"continuity\""
            ),
        }
        let almanac_path = match (&c.almanac, &c.navigation) {
            (Some(a), None) => a.clone(),
            (None, Some(nav)) => {
                if c.week_rollovers.is_some()
                    || c.id_offset != 0
                    || c.format != AlmanacFormat::Yuma
                    || c.add_almanac.is_some()
                    || !c.add.is_empty()
                {
                    bail!(
                        "{here}: week_rollovers, id_offset, format, add_almanac and add are almanac keys, not read with `navigation`"
                    );
                }
                let p = almanac::resolve(base, nav);
                let data = match navs.get(&p) {
                    Some(d) => Arc::clone(d),
                    None => {
                        let d = Arc::new(
                            raim_gnss::NavData::load(&p)
                                .map_err(|e| anyhow!("{}: {e}", p.display()))?,
                        );
                        navs.insert(p.clone(), Arc::clone(&d));
                        d
                    }
                };
                let ids: Vec<SatId> = data
                    .ephemerides
                    .keys()
                    .filter(|id| id.system == system)
                    .copied()
                    .collect();
                if ids.is_empty() {
                    bail!("{}: no {system:?} ephemeris ({here})", p.display());
                }
                for r in &c.remove {
                    if !ids.iter().any(|id| id.prn == *r) {
                        bail!(
                            "{here}: remove = PRN {r}, which has no ephemeris in {}",
                            p.display()
                        );
                    }
                }
                let first_toc = data
                    .ephemerides
                    .iter()
                    .filter(|(id, _)| id.system == system)
                    .flat_map(|(_, v)| v.iter().map(|k| k.toc_gps_s))
                    .fold(f64::INFINITY, f64::min);
                week0.get_or_insert((first_toc / raim_nav::ephemeris::WEEK_S).floor() as u32);
                for id in ids.into_iter().filter(|id| !c.remove.contains(&id.prn)) {
                    entries.push(SatIsm {
                        id,
                        sigma_ura_m: c.sigma_ura_m,
                        sigma_ure_m: c.sigma_ure_m,
                        b_nom_m: c.b_nom_m,
                        p_sat: c.p_sat,
                    });
                    sats.push(StudySat {
                        id,
                        orbit: Orbit::Broadcast(Arc::clone(&data)),
                    });
                }
                check_ism(c, system)
                    .map_err(|e| anyhow!("{here}: the ISM is refused by raim-core: {e}"))?;
                continue;
            }
            _ => bail!("{here}: give the constellation's `almanac` or `navigation` (one of them)"),
        };
        let read_alm = |p: &Path| {
            let spec = AlmanacSpec {
                path: almanac::resolve(base, p),
                system,
                id_offset: c.id_offset,
                week_rollovers: c.week_rollovers,
            };
            match c.format {
                AlmanacFormat::Yuma => almanac::read(&spec),
                AlmanacFormat::Sem => almanac::read_sem(&spec),
            }
        };
        let mut alm = read_alm(&almanac_path)?;
        for p in &c.remove {
            if !alm.sats.iter().any(|s| s.kepler.prn == *p) {
                bail!(
                    "{here}: remove = PRN {p}, which is not a healthy satellite of {}",
                    almanac_path.display()
                );
            }
        }
        match (&c.add_almanac, c.add.is_empty()) {
            (Some(path), false) => {
                let extra = read_alm(path)?;
                let mut sorted = c.add.clone();
                sorted.sort_unstable();
                if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
                    bail!("{}: add lists PRN {} twice", at("add"), w[0]);
                }
                for p in &c.add {
                    let Some(s) = extra.sats.iter().find(|s| s.kepler.prn == *p) else {
                        bail!(
                            "{}: add = PRN {p}, which is not a healthy satellite of {}",
                            at("add"),
                            path.display()
                        );
                    };
                    if alm.sats.iter().any(|k| k.kepler.prn == *p) && !c.remove.contains(p) {
                        bail!(
                            "{}: add = PRN {p}, which {} holds already (list it in `remove` to replace it)",
                            at("add"),
                            almanac_path.display()
                        );
                    }
                    alm.sats.retain(|k| k.kepler.prn != *p);
                    alm.sats.push(*s);
                }
            }
            (None, true) => {}
            (None, false) => bail!(
                "{}: add needs `add_almanac`, the file to take them from",
                at("add")
            ),
            (Some(_), true) => bail!(
                "{}: add_almanac without `add` (the PRNs to take)",
                at("add_almanac")
            ),
        }
        unhealthy.extend(
            alm.unhealthy
                .iter()
                .map(|p| format!("{}{p:02}", system.letter())),
        );
        let mut kept: Vec<_> = alm
            .sats
            .into_iter()
            .filter(|s| !c.remove.contains(&s.kepler.prn) || c.add.contains(&s.kepler.prn))
            .collect();
        kept.sort_by_key(|s| s.kepler.prn);
        for s in kept {
            let id = SatId::new(system, s.kepler.prn);
            week0.get_or_insert(s.week);
            entries.push(SatIsm {
                id,
                sigma_ura_m: c.sigma_ura_m,
                sigma_ure_m: c.sigma_ure_m,
                b_nom_m: c.b_nom_m,
                p_sat: c.p_sat,
            });
            sats.push(StudySat {
                id,
                orbit: Orbit::Almanac(s.kepler),
            });
            let from = match &c.add_almanac {
                Some(a) if c.add.contains(&s.kepler.prn) => a.clone(),
                _ => almanac_path.clone(),
            };
            almanac_sats.push((from, s));
        }
        check_ism(c, system)
            .map_err(|e| anyhow!("{here}: the ISM is refused by raim-core: {e}"))?;
    }
    ism.validate()
        .map_err(|e| anyhow!("{file}: the ISM is refused by raim-core: {e}"))?;
    if sats.len() > crate::engine::N_SATS {
        bail!(
            "{file}: {} satellites; the engine holds {}",
            sats.len(),
            crate::engine::N_SATS
        );
    }
    let Some(week0) = week0 else {
        bail!("{file}: no satellite left after the outages");
    };
    let t0 = f64::from(week0) * raim_nav::ephemeris::WEEK_S + t.start_s;
    let epochs_gps_s: Vec<f64> = (0..n_epochs).map(|k| t0 + k as f64 * t.step_s).collect();
    // Kepler::state places t within half a week of the time of
    // applicability (IS-GPS-200's crossover): a span beyond that would be
    // silently moved by a week.
    let (first, last) = (t0, t0 + (n_epochs - 1) as f64 * t.step_s);
    for (alm, s) in &almanac_sats {
        let toa = s.kepler.toc_gps_s;
        let half = raim_nav::ephemeris::WEEK_S / 2.0;
        if (first - toa).abs() > half || (last - toa).abs() > half {
            bail!(
                "{}:{}: the run's epochs [{first}, {last}] s (GPS) are more than half a week from \
                 this almanac's time of applicability {toa} s: move [time] start_s ({})",
                almanac::resolve(base, alm).display(),
                s.line,
                at("start_s")
            );
        }
    }
    // A broadcast satellite with no healthy set valid at any epoch of the
    // run is left out (listed with the unhealthy ones).
    let never: Vec<bool> = sats
        .iter()
        .map(|s| s.is_broadcast() && epochs_gps_s.iter().all(|t| s.kepler_at(*t).is_none()))
        .collect();
    for (s, _) in sats.iter().zip(&never).filter(|(_, n)| **n) {
        unhealthy.push(format!("{}{:02}", s.id.system.letter(), s.id.prn));
    }
    let mut k = never.iter();
    sats.retain(|_| !k.next().copied().unwrap_or(false));
    let mut k = never.iter();
    entries.retain(|_| !k.next().copied().unwrap_or(false));
    if sats.is_empty() {
        bail!("{file}: no satellite has a healthy ephemeris valid at an epoch of the run");
    }
    Ok(Study {
        name: run.name.clone(),
        sats,
        ism_entries: entries,
        ism,
        cfg,
        criteria,
        budgets: if criteria == Criteria::HorizontalOnly {
            run.service.phmi.zip(run.service.p_fa).map(|(a, b)| [a, b])
        } else {
            None
        },
        target,
        exclusion: run.exclusion,
        continuity,
        estimator,
        airborne,
        mask_rad: run.mask_deg.to_radians(),
        height_m: run.height_m,
        users,
        epochs_gps_s,
        unhealthy,
        source: loc.text().to_string(),
    })
}

/// A constellation's ISM against raim-core's own satellite check
/// (`AraimSat::validate`: the operational bounds of sigma, b_nom, P_sat)
/// at a zenith satellite.
fn check_ism(c: &ConstellationSpec, system: System) -> Result<()> {
    if c.sigma_ure_m.is_nan() || c.sigma_ure_m > c.sigma_ura_m {
        bail!(
            "sigma_ure_m {} above sigma_ura_m {} (C_acc must not exceed C_int)",
            c.sigma_ure_m,
            c.sigma_ura_m
        );
    }
    let el = core::f64::consts::FRAC_PI_2;
    let (c_int, c_acc) =
        raim_core::araim::error_model::variances_m2(el, c.sigma_ura_m, c.sigma_ure_m);
    let sat = raim_core::araim::AraimSat {
        id: SatId::new(system, 1),
        g_enu: [0.0, 0.0, -1.0],
        c_int_m2: c_int,
        c_acc_m2: c_acc,
        b_nom_m: c.b_nom_m,
        p_sat: c.p_sat,
        residual_m: 0.0,
    };
    sat.validate(0).map_err(|e| anyhow!("{e}"))?;
    Ism::with(&[system], c.p_const)
        .validate()
        .map_err(|e| anyhow!("{e}"))
}

/// The grid's users, south to north then west to east.
fn users(g: &GridSpec) -> Result<Vec<User>> {
    let user = |lat: f64, lon: f64, name: String| User {
        name,
        lat_deg: lat,
        lon_deg: lon,
        weight: lat.to_radians().cos().max(0.0),
    };
    // Steps are counted in integers so that every node is k * step exactly.
    let axis = |lo: f64, hi: f64, step: f64, closed: bool| -> Result<Vec<f64>> {
        if !(step > 0.0 && step.is_finite() && lo.is_finite() && hi.is_finite() && lo <= hi) {
            bail!("bad grid axis [{lo}, {hi}] at step {step}");
        }
        let n = ((hi - lo) / step + 1e-9).floor() as usize;
        let mut v: Vec<f64> = (0..=n).map(|k| lo + k as f64 * step).collect();
        if !closed && v.last().is_some_and(|x| (*x - hi).abs() < 1e-9) {
            v.pop();
        }
        Ok(v)
    };
    let grid = |lats: Vec<f64>, lons: Vec<f64>| {
        lats.iter()
            .flat_map(|&la| lons.iter().map(move |&lo| (la, lo)))
            .map(|(la, lo)| user(la, lo, String::new()))
            .collect::<Vec<_>>()
    };
    match g {
        GridSpec::World { step_deg } => Ok(grid(
            axis(-90.0, 90.0, *step_deg, true)?,
            axis(-180.0, 180.0, *step_deg, false)?,
        )),
        GridSpec::Region {
            step_deg,
            lat_min_deg,
            lat_max_deg,
            lon_min_deg,
            lon_max_deg,
        } => {
            if *lat_min_deg < -90.0 || *lat_max_deg > 90.0 {
                bail!("region latitudes [{lat_min_deg}, {lat_max_deg}] beyond +-90");
            }
            Ok(grid(
                axis(*lat_min_deg, *lat_max_deg, *step_deg, true)?,
                axis(*lon_min_deg, *lon_max_deg, *step_deg, true)?,
            ))
        }
        GridSpec::Sites { sites } => sites
            .iter()
            .map(|s| {
                if s.name.contains([',', '"', '\n', '\r']) {
                    bail!("site `{}`: a name without commas, quotes or line breaks (it is a CSV field)", s.name);
                }
                if !(-90.0..=90.0).contains(&s.lat_deg) || !s.lon_deg.is_finite() {
                    bail!(
                        "site `{}`: latitude {} outside [-90, 90]",
                        s.name,
                        s.lat_deg
                    );
                }
                Ok(user(s.lat_deg, s.lon_deg, s.name.clone()))
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn data() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data")
    }

    /// The MAAST run file's text with `grid` and `extra` (top-level keys)
    /// in place of its grid, almanacs from the shared data.
    fn text(grid: &str, service: &str, gps_extra: &str) -> String {
        format!(
            r#"name = "t"
mask_deg = 5.0
[time]
start_s = 345600.0
span_s = 900.0
step_s = 300.0
{grid}
[service]
{service}
[[constellation]]
system = "G"
almanac = "almanac_gps24_mops.yuma"
week_rollovers = 0
{gps_extra}
sigma_ura_m = 1.0
sigma_ure_m = 0.5
b_nom_m = 0.75
p_sat = 1e-5
p_const = 1e-8
"#
        )
    }

    fn load_text(t: &str) -> Result<Study> {
        from_text(t, Path::new("t.toml"), &data())
    }

    /// Verifies: SPEC-14
    #[test]
    fn grids_and_weights() {
        let s = load_text(&text(
            "[grid]\nkind = \"world\"\nstep_deg = 10.0",
            "level = \"LPV-200\"",
            "",
        ))
        .unwrap();
        // 19 latitudes (-90..=90) x 36 longitudes (-180..<180).
        assert_eq!(s.users.len(), 19 * 36);
        assert_eq!((s.users[0].lat_deg, s.users[0].lon_deg), (-90.0, -180.0));
        assert_eq!(
            s.users.last().map(|u| (u.lat_deg, u.lon_deg)),
            Some((90.0, 170.0))
        );
        let u60 = s.users.iter().find(|u| u.lat_deg == 60.0).unwrap();
        assert!((u60.weight - 0.5).abs() < 1e-15);
        assert_eq!(s.epochs_gps_s.len(), 3);
        assert_eq!(s.epochs_gps_s[0], 703.0 * 604_800.0 + 345_600.0);
        let r = load_text(&text(
            "[grid]\nkind = \"region\"\nstep_deg = 5.0\nlat_min_deg = 40.0\nlat_max_deg = 50.0\nlon_min_deg = -5.0\nlon_max_deg = 5.0",
            "level = \"LPV-200\"",
            "",
        ))
        .unwrap();
        assert_eq!(r.users.len(), 9);
        let sites = load_text(&text(
            "[grid]\nkind = \"sites\"\nsites = [{ name = \"LFPG\", lat_deg = 49.0097, lon_deg = 2.5479 }]",
            "level = \"LPV-200\"",
            "",
        ))
        .unwrap();
        assert_eq!(sites.users.len(), 1);
        assert_eq!(sites.users[0].name, "LFPG");
        let e = load_text(&text(
            "[grid]\nkind = \"sites\"\nsites = [{ name = \"Paris, CDG\", lat_deg = 49.0, lon_deg = 2.5 }]",
            "level = \"LPV-200\"",
            "",
        ))
        .unwrap_err();
        assert!(e.to_string().contains("without commas"), "{e}");
    }

    #[test]
    fn service_levels_and_outages() {
        let grid = "[grid]\nkind = \"world\"\nstep_deg = 30.0";
        let s = load_text(&text(grid, "level = \"LPV-250\"", "remove = [3, 17]")).unwrap();
        assert_eq!(s.cfg.val_m, 50.0);
        assert_eq!(s.cfg.hal_m, 40.0);
        assert_eq!(s.sats.len(), 22);
        assert!(!s.sats.iter().any(|x| x.id.prn == 3 || x.id.prn == 17));
        let c = load_text(&text(
            grid,
            "level = \"custom\"\nval_m = 50.0\nhal_m = 100.0\nemt_max_m = 20.0\nsigma_acc_max_m = 2.0",
            "",
        ))
        .unwrap();
        assert_eq!(
            [
                c.cfg.val_m,
                c.cfg.hal_m,
                c.cfg.emt_max_m,
                c.cfg.sigma_acc_max_m
            ],
            [50.0, 100.0, 20.0, 2.0]
        );
        let e = load_text(&text(grid, "level = \"LPV-200\"", "remove = [25]")).unwrap_err();
        assert!(e.to_string().contains("remove = PRN 25"), "{e}");
        let e = load_text(&text(grid, "level = \"LPV-200\"\nval_m = 10.0", "")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.toml:11: limits are given only with level = \"custom\""
        );
        let e = load_text(&text(grid, "level = \"CAT-I\"", "")).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("t.toml:11: unknown service level `CAT-I`"),
            "{e}"
        );
        let e = load_text(&text(
            "[grid]\nkind = \"sites\"\nsites = []",
            "level = \"LPV-200\"",
            "",
        ))
        .unwrap_err();
        assert_eq!(e.to_string(), "t.toml:8: the grid has no user");
        let e = load_text(&text(grid, "level = \"LPV-200\"\ntypo = 1", "")).unwrap_err();
        assert!(
            e.to_string().starts_with("t.toml:12: unknown field `typo`"),
            "{e}"
        );
    }

    /// `position`: the plain estimator by default; `"adjusted"` with the
    /// service level's sigma_acc limit on every axis unless
    /// `adjusted_sigma_acc_max_m` gives them; the limits refused without
    /// `position = "adjusted"` or out of raim-core's bound, an unknown
    /// estimator refused, each named by its line.
    ///
    /// Verifies: TOOL-AVAIL-ADJUSTED
    #[test]
    fn the_position_estimator_keys() {
        let grid = "[grid]\nkind = \"world\"\nstep_deg = 30.0";
        let with = |top: &str| {
            text(grid, "level = \"LPV-200\"", "").replacen(
                "mask_deg = 5.0\n",
                &format!("mask_deg = 5.0\n{top}\n"),
                1,
            )
        };
        assert_eq!(
            load_text(&with("")).unwrap().estimator,
            Estimator::AllInView
        );
        assert_eq!(
            load_text(&with("position = \"adjusted\""))
                .unwrap()
                .estimator,
            Estimator::Adjusted {
                sigma_acc_max_m: [1.87; 3]
            }
        );
        assert_eq!(
            load_text(&with(
                "position = \"adjusted\"\nadjusted_sigma_acc_max_m = [3.0, 3.0, 1.86]"
            ))
            .unwrap()
            .estimator,
            Estimator::Adjusted {
                sigma_acc_max_m: [3.0, 3.0, 1.86]
            }
        );
        let e = load_text(&with("adjusted_sigma_acc_max_m = [3.0, 3.0, 1.86]")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.toml:3: adjusted_sigma_acc_max_m is read only with position = \"adjusted\""
        );
        let e = load_text(&with(
            "position = \"adjusted\"\nadjusted_sigma_acc_max_m = [3.0, 30.0, 1.86]",
        ))
        .unwrap_err();
        assert!(
            e.to_string().starts_with("t.toml:4: ")
                && e.to_string().contains("adjusted_sigma_acc_max_m"),
            "{e}"
        );
        let e = load_text(&with("position = \"optimal\"")).unwrap_err();
        assert!(e.to_string().contains("unknown variant `optimal`"), "{e}");
    }

    /// Satellites added by PRN from a second almanac (written here in
    /// YUMA: PRN 30 on PRN 3's orbit half a revolution ahead, and PRN 3
    /// moved by 0.5 rad): 25 GPS satellites with PRN 30's and the new PRN
    /// 3's orbits when PRN 3 is removed and both added; a constellation
    /// read from a SEM file (`format = "sem"`, the same two records); bad
    /// add lists named by the run file's line.
    ///
    /// Verifies: TOOL-AVAIL-SEM
    #[test]
    fn satellites_added_from_a_second_almanac() {
        let dir = std::env::temp_dir().join(format!("raim-avail-add-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let yuma = crate::almanac::read(&AlmanacSpec {
            path: data().join("almanac_gps24_mops.yuma"),
            system: System::Gps,
            id_offset: 0,
            week_rollovers: Some(0),
        })
        .unwrap();
        let k = yuma.sats[2].kepler;
        let pi = core::f64::consts::PI;
        let (m30, m3) = (k.m0_rad + pi, k.m0_rad + 0.5);
        let yrec = |prn: u8, m0: f64| {
            format!(
                "**** PRN {prn} ****\nID: {prn}\nHealth: 000\nEccentricity: {:e}\nTime of Applicability(s): {}\n\
                 Orbital Inclination(rad): {:e}\nRate of Right Ascen(r/s): {:e}\nSQRT(A)  (m 1/2): {:e}\n\
                 Right Ascen at Week(rad): {:e}\nArgument of Perigee(rad): {:e}\nMean Anom(rad): {:e}\n\
                 Af0(s): 0.0\nAf1(s/s): 0.0\nweek: 703\n\n",
                k.e, k.toe_sow_s, k.i0_rad, k.omega_dot_rad_s, k.sqrt_a_m05, k.omega0_rad, k.omega_rad, m0
            )
        };
        let srec = |prn: u8, m0: f64| {
            format!(
                "{prn}\n{prn}\n0\n {:.15E} {:.15E} {:.15E}\n {:.15E} {:.15E} {:.15E}\n {:.15E} 0.0 0.0\n0\n11\n\n",
                k.e, k.i0_rad / pi - 0.30, k.omega_dot_rad_s / pi,
                k.sqrt_a_m05, k.omega0_rad / pi, k.omega_rad / pi, m0 / pi
            )
        };
        let extra = dir.join("extra.yuma");
        std::fs::write(&extra, format!("{}{}", yrec(30, m30), yrec(3, m3))).unwrap();
        let sem = dir.join("extra.sem");
        std::fs::write(
            &sem,
            format!(
                "2 EXTRA\n 703 {}\n\n{}{}",
                k.toe_sow_s,
                srec(30, m30),
                srec(3, m3)
            ),
        )
        .unwrap();
        let grid = "[grid]\nkind = \"world\"\nstep_deg = 30.0";
        let add_from = format!("add_almanac = \"{}\"", extra.display());
        let run = |lines: &str| load_text(&text(grid, "level = \"LPV-200\"", lines));
        let s = run(&format!("remove = [3]\n{add_from}\nadd = [30, 3]")).unwrap();
        let prns: Vec<u8> = s.sats.iter().map(|x| x.id.prn).collect();
        assert_eq!(prns, (1..=24).chain([30]).collect::<Vec<u8>>());
        assert!((s.sats[2].kepler_at(0.0).unwrap().m0_rad - m3).abs() < 1e-12);
        assert!((s.sats[24].kepler_at(0.0).unwrap().m0_rad - m30).abs() < 1e-12);
        // The same two records as a SEM constellation.
        let t = text(grid, "level = \"LPV-200\"", "").replace(
            "almanac = \"almanac_gps24_mops.yuma\"",
            &format!("almanac = \"{}\"\nformat = \"sem\"", sem.display()),
        );
        let s = load_text(&t).unwrap();
        let got: Vec<(u8, f64)> = s
            .sats
            .iter()
            .map(|x| (x.id.prn, x.kepler_at(0.0).unwrap().m0_rad))
            .collect();
        assert_eq!(got.len(), 2);
        assert!(got[0].0 == 3 && (got[0].1 - m3).abs() < 1e-12 && got[1].0 == 30);
        // Bad add lists.
        let e = run(&format!("{add_from}\nadd = [3]")).unwrap_err();
        assert!(e.to_string().contains("holds already"), "{e}");
        let e = run("add = [30]").unwrap_err();
        assert!(e.to_string().contains("add needs `add_almanac`"), "{e}");
        let e = run(&format!("{add_from}\nadd = [31]")).unwrap_err();
        assert!(e.to_string().starts_with("t.toml:"), "{e}");
        assert!(
            e.to_string()
                .contains("add = PRN 31, which is not a healthy satellite"),
            "{e}"
        );
        let e = run(&format!("{add_from}\nadd = [30, 30]")).unwrap_err();
        assert!(e.to_string().contains("add lists PRN 30 twice"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A horizontal-only level with its own budgets (`phmi`, `p_fa`):
    /// at every user-epoch of a small GPS study (4 users x 3 epochs) the
    /// engine's HPL equals the HPL raim-core gives on the same sky for an
    /// allocation written out here (PHMI_VERT and P_FA_VERT at the core's
    /// floors of 1e-9, the horizontal budgets the rest), bit for bit, and
    /// the level is available exactly when that HPL is within the HAL (40
    /// m, met at some user-epochs and not at others: sigma_URA 7 m); the
    /// budget is not ignored: the LPV-200 allocation (PHMI_HOR 2e-9,
    /// P_FA_HOR 9e-8) gives a larger HPL at every user-epoch, above the
    /// HAL at some that the level's own budget makes available. A missing
    /// budget, a budget with an LPV level, a budget at the floor and one
    /// the core refuses (PHMI below P_THRES) are refused by line.
    ///
    /// Verifies: TOOL-AVAIL-HARAIM-BUDGET
    #[test]
    fn horizontal_level_budgets_flow_into_the_core() {
        std::thread::Builder::new()
            .stack_size(crate::engine::STACK_BYTES)
            .spawn(horizontal_budgets_body)
            .expect("spawn")
            .join()
            .expect("the test body panicked");
    }

    fn horizontal_budgets_body() {
        use raim_core::araim::FdeLimits;
        let grid = "[grid]\nkind = \"region\"\nstep_deg = 30.0\nlat_min_deg = 0.0\nlat_max_deg = 30.0\nlon_min_deg = 0.0\nlon_max_deg = 30.0";
        let (phmi, p_fa) = (1e-7, 4e-6);
        // sigma_URA 7 m: HPLs about the HAL's floor of 40 m.
        let sky = |service: &str| {
            text(grid, service, "").replace("sigma_ura_m = 1.0", "sigma_ura_m = 7.0")
        };
        let own = load_text(&sky(&format!(
            "level = \"custom-horizontal\"\nhal_m = 40.0\nphmi = {phmi:e}\np_fa = {p_fa:e}"
        )))
        .unwrap();
        let lpv = load_text(&sky("level = \"LPV-200\"")).unwrap();
        assert_eq!(own.budgets, Some([phmi, p_fa]));
        let by_hand = AraimConfig {
            phmi_vert: 1e-9,
            phmi_hor: phmi - 1e-9,
            pfa_vert: 1e-9,
            pfa_hor: p_fa - 1e-9,
            hal_m: 40.0,
            ..AraimConfig::default()
        };
        let mut m = crate::engine::new_engine();
        let mut core = crate::engine::new_engine();
        let (mut seen, mut avail, mut only_own) = (0, 0, 0);
        for u in &own.users {
            let (x, r) = crate::engine::user_frame(&own, u);
            for k in 0..own.epochs_gps_s.len() {
                let sky = crate::engine::sky_table(&own, k..k + 1);
                let mut obs = Vec::new();
                crate::engine::visible(&own, &sky, x, &r, &mut obs);
                let h = crate::engine::evaluate(&own, &mut m, &obs).unwrap();
                let l = crate::engine::evaluate(&lpv, &mut m, &obs).unwrap();
                core.linear(
                    &by_hand,
                    &own.ism,
                    &own.ism_entries[..],
                    &obs,
                    FdeLimits::UNLIMITED,
                )
                .unwrap();
                let hpl = core.in_force().pl_add.hpl_m;
                assert_eq!(
                    h.hpl_m.to_bits(),
                    hpl.to_bits(),
                    "HPL {} against the core's {hpl}",
                    h.hpl_m
                );
                assert_eq!(h.available, hpl <= 40.0, "HPL {hpl}");
                assert!(
                    l.hpl_m > h.hpl_m,
                    "LPV-200 allocation HPL {} <= {}",
                    l.hpl_m,
                    h.hpl_m
                );
                seen += 1;
                only_own += usize::from(h.available && l.hpl_m > 40.0);
                avail += usize::from(h.available);
            }
        }
        assert_eq!(seen, 12);
        assert!(
            avail > 0 && avail < seen,
            "{avail} of {seen} available: the HAL decides nothing"
        );
        assert!(only_own > 0, "the budget changes no decision");
        let err = |service: &str| load_text(&text(grid, service, "")).unwrap_err().to_string();
        let e = err("level = \"H-ARAIM-NPA\"");
        assert!(
            e.contains("t.toml:") && e.contains("needs its own budgets"),
            "{e}"
        );
        let e = err("level = \"LPV-200\"\nphmi = 1e-7\np_fa = 4e-6");
        assert!(e.contains("only with a horizontal-only level"), "{e}");
        let e = err("level = \"H-ARAIM-NPA\"\nphmi = 2e-9\np_fa = 4e-6");
        assert!(e.contains("phmi 0.000000002 outside"), "{e}");
        let e = err("level = \"H-ARAIM-NPA\"\nphmi = 5e-8\np_fa = 4e-6");
        assert!(
            e.contains("refused by raim-core") && e.contains("p_thres"),
            "{e}"
        );
    }
}
