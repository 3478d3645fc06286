//! Outputs: the JSON summary, the per-user CSV, and the partial result of
//! a shard, which `merge` combines exactly (the PL values travel as their
//! IEEE bits, and every summary is a function of the multiset of a user's
//! values: 4 shards merged give the single run's files byte for byte).

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{anyhow, bail, Context, Result};
use serde::{Deserialize, Serialize};

use crate::engine::{UserPartial, UserSummary, PERCENTILE};
use crate::run::Study;

/// The partial file's format tag.
pub const PARTIAL_FORMAT: &str = "raim-availability-partial/2";

/// What the summary needs besides the users' results (carried by each
/// partial so that `merge` needs no run file).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Meta {
    /// The scenario's name.
    pub name: String,
    /// FNV-1a 64 of the run file's text (hex): shards of one run only.
    pub run_digest: String,
    /// The satellites in use.
    pub satellites: Vec<String>,
    /// Unhealthy satellites left out.
    pub unhealthy: Vec<String>,
    /// Epochs of the whole run.
    pub epochs: usize,
    /// The mask (rad).
    pub mask_rad: f64,
    /// VAL, HAL, EMT limit, sigma_v,acc limit (m).
    pub limits_m: [f64; 4],
    /// The availability target.
    pub target: f64,
    /// The users: name, latitude, longitude (degrees), weight.
    pub users: Vec<(String, f64, f64, f64)>,
    /// With a broadcast (RINEX) constellation: per satellite, the epochs
    /// of the run at which it had no healthy ephemeris within its validity
    /// window and was not used (satellites with none are not listed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ephemeris_gaps: Option<Vec<(String, usize)>>,
    /// The service level judges the HAL alone (H-ARAIM).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub horizontal_only: bool,
    /// A horizontal-only level's own budgets (PHMI, P_FA per epoch; the
    /// run file's `phmi`, `p_fa`): raim-core's PHMI_VERT + PHMI_HOR and
    /// P_FA_VERT + P_FA_HOR (`run::horizontal_budgets`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub budgets: Option<[f64; 2]>,
    /// `position = "adjusted"`: the adjusted estimator's accuracy limits
    /// per axis E, N, U (m); `None` for the plain estimator.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub adjusted_sigma_acc_max_m: Option<[f64; 3]>,
}

/// FNV-1a, 64 bits.
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(*b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

impl Meta {
    /// The study's metadata.
    pub fn of(study: &Study) -> Meta {
        Meta {
            name: study.name.clone(),
            run_digest: format!("{:016x}", fnv1a64(study.source.as_bytes())),
            satellites: study
                .sats
                .iter()
                .map(|s| format!("{}{:02}", s.id.system.letter(), s.id.prn))
                .collect(),
            unhealthy: study.unhealthy.clone(),
            epochs: study.epochs_gps_s.len(),
            mask_rad: study.mask_rad,
            limits_m: [
                study.cfg.val_m,
                study.cfg.hal_m,
                study.cfg.emt_max_m,
                study.cfg.sigma_acc_max_m,
            ],
            target: study.target,
            users: study
                .users
                .iter()
                .map(|u| (u.name.clone(), u.lat_deg, u.lon_deg, u.weight))
                .collect(),
            horizontal_only: study.criteria == raim_core::araim::Criteria::HorizontalOnly,
            budgets: study.budgets,
            adjusted_sigma_acc_max_m: match study.estimator {
                raim_core::araim::Estimator::AllInView => None,
                raim_core::araim::Estimator::Adjusted { sigma_acc_max_m } => Some(sigma_acc_max_m),
            },
            ephemeris_gaps: study.sats.iter().any(|s| s.is_broadcast()).then(|| {
                study
                    .sats
                    .iter()
                    .map(|s| {
                        let gaps = study
                            .epochs_gps_s
                            .iter()
                            .filter(|t| s.kepler_at(**t).is_none())
                            .count();
                        (format!("{}{:02}", s.id.system.letter(), s.id.prn), gaps)
                    })
                    .filter(|(_, n)| *n > 0)
                    .collect()
            }),
        }
    }
}

/// One scenario's metadata and per-user summaries.
pub type ScenarioResult = (Meta, Vec<UserSummary>);

/// The scenarios of a run as the partial files and `merge` see them.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepHead {
    /// The run's name.
    pub name: String,
    /// The coverage table's tag (`outages`, `sweep`), none for one scenario.
    pub table: Option<String>,
    /// Per scenario, in order: its output stem and the satellite an outage
    /// removed (`none`).
    pub scenarios: Vec<[String; 2]>,
    /// Epochs of every scenario (the run's time span).
    pub epochs: usize,
}

impl SweepHead {
    /// The sweep's head.
    pub fn of(sweep: &crate::sweep::Sweep) -> SweepHead {
        SweepHead {
            name: sweep.name.clone(),
            table: sweep.table.clone(),
            scenarios: sweep
                .scenarios
                .iter()
                .map(|s| [s.study.name.clone(), s.removed.clone()])
                .collect(),
            epochs: sweep
                .scenarios
                .first()
                .map_or(0, |s| s.study.epochs_gps_s.len()),
        }
    }
}

/// One shard's results: the scenario x epoch blocks of [`shard_pieces`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Partial {
    /// [`PARTIAL_FORMAT`].
    pub format: String,
    /// The run's scenarios.
    pub head: SweepHead,
    /// This shard, 1-based.
    pub shard: usize,
    /// Shards of the run.
    pub shards: usize,
    /// The shard's pieces, in scenario order.
    pub pieces: Vec<Piece>,
}

/// One scenario's epochs within a shard.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Piece {
    /// The scenario.
    pub meta: Meta,
    /// The epochs, [first, end).
    pub epoch_range: [usize; 2],
    /// Per user (in `meta.users` order).
    pub users: Vec<PartialUser>,
}

/// The pieces of shard `i` (1-based) of `n` over `scenarios` x `epochs`:
/// the units (scenario, epoch) in scenario-major order split into `n`
/// contiguous blocks ([`shard_range`]), each cut at the scenarios'
/// boundaries. With n = scenarios a shard is one scenario; with more, a
/// scenario's epochs are split in time; with fewer, a shard holds several.
pub fn shard_pieces(
    scenarios: usize,
    epochs: usize,
    i: usize,
    n: usize,
) -> Vec<(usize, std::ops::Range<usize>)> {
    let r = shard_range(scenarios * epochs, i, n);
    (0..scenarios)
        .filter_map(|s| {
            let (a, b) = (r.start.max(s * epochs), r.end.min((s + 1) * epochs));
            (a < b).then(|| (s, a - s * epochs..b - s * epochs))
        })
        .collect()
}

/// One user's shard, the floats as IEEE-754 bits.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PartialUser {
    /// Epochs.
    pub epochs: u32,
    /// Available epochs.
    pub available: u32,
    /// Most monitored modes.
    pub max_modes: u32,
    /// Refused epochs.
    pub refused: u32,
    /// VPL bits per epoch.
    pub vpl_bits: Vec<u64>,
    /// HPL bits per epoch.
    pub hpl_bits: Vec<u64>,
    /// EMT bits per epoch.
    pub emt_bits: Vec<u64>,
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

fn floats(v: &[u64]) -> Vec<f64> {
    v.iter().map(|x| f64::from_bits(*x)).collect()
}

impl From<&UserPartial> for PartialUser {
    fn from(p: &UserPartial) -> Self {
        PartialUser {
            epochs: p.epochs,
            available: p.available,
            max_modes: p.max_modes,
            refused: p.refused,
            vpl_bits: bits(&p.vpl_m),
            hpl_bits: bits(&p.hpl_m),
            emt_bits: bits(&p.emt_m),
        }
    }
}

impl From<&PartialUser> for UserPartial {
    fn from(p: &PartialUser) -> Self {
        UserPartial {
            epochs: p.epochs,
            available: p.available,
            vpl_m: floats(&p.vpl_bits),
            hpl_m: floats(&p.hpl_bits),
            emt_m: floats(&p.emt_bits),
            max_modes: p.max_modes,
            refused: p.refused,
        }
    }
}

/// Epochs `[a, b)` of shard `i` (1-based) of `n` over `epochs`: contiguous
/// blocks, the first `epochs % n` one epoch longer.
pub fn shard_range(epochs: usize, i: usize, n: usize) -> std::ops::Range<usize> {
    let (q, r) = (epochs / n, epochs % n);
    let k = i - 1;
    let a = k * q + k.min(r);
    a..a + q + usize::from(k < r)
}

/// Parses `i/n` (1 <= i <= n).
///
/// # Errors
/// Not of that form.
pub fn parse_shard(s: &str) -> Result<(usize, usize)> {
    let bad = || anyhow!("--shard `{s}`: expected i/n with 1 <= i <= n");
    let (i, n) = s.split_once('/').ok_or_else(bad)?;
    let (i, n): (usize, usize) = (i.parse().map_err(|_| bad())?, n.parse().map_err(|_| bad())?);
    if i == 0 || i > n {
        return Err(bad());
    }
    Ok((i, n))
}

/// Reads the partial files and combines them into per-scenario, per-user
/// summaries: every shard 1..n of one run exactly once, each holding the
/// pieces [`shard_pieces`] assigns it, a scenario's pieces concatenated in
/// epoch order.
///
/// # Errors
/// An unreadable or malformed file, files of different runs, a shard
/// missing or given twice, pieces or user lists that differ from the head.
pub fn merge(paths: &[std::path::PathBuf]) -> Result<(SweepHead, Vec<ScenarioResult>)> {
    let mut parts = Vec::new();
    for p in paths {
        let text = std::fs::read_to_string(p).with_context(|| p.display().to_string())?;
        let format: serde_json::Value = serde_json::from_str(&text)
            .map_err(|e| anyhow!("{}:{}: {e}", p.display(), e.line()))?;
        if format["format"] != PARTIAL_FORMAT {
            bail!(
                "{}: format {}, expected `{PARTIAL_FORMAT}`",
                p.display(),
                format["format"]
            );
        }
        let part: Partial = serde_json::from_str(&text)
            .map_err(|e| anyhow!("{}:{}: {e}", p.display(), e.line()))?;
        parts.push((p.clone(), part));
    }
    let Some((first_path, first)) = parts.first() else {
        bail!("merge: no partial file given");
    };
    let n = first.shards;
    let head = &first.head;
    let mut slot: Vec<Option<usize>> = vec![None; n];
    for (k, (p, part)) in parts.iter().enumerate() {
        if part.head != *head || part.shards != n {
            bail!(
                "{}: not a shard of the run of {} (different run, scenarios or shard count)",
                p.display(),
                first_path.display()
            );
        }
        if part.shard == 0 || part.shard > n {
            bail!("{}: shard {} of {n}", p.display(), part.shard);
        }
        let want = shard_pieces(head.scenarios.len(), head.epochs, part.shard, n);
        let matches = want.len() == part.pieces.len()
            && want.iter().zip(&part.pieces).all(|((s, r), piece)| {
                piece.meta.name == head.scenarios[*s][0]
                    && piece.epoch_range == [r.start, r.end]
                    && piece.meta.epochs == head.epochs
                    && piece.users.len() == piece.meta.users.len()
                    && piece
                        .users
                        .iter()
                        .all(|u| u.vpl_bits.len() == r.len() && u.epochs as usize == r.len())
            });
        if !matches {
            bail!(
                "{}: the shard's scenarios, epochs or users do not match its header",
                p.display()
            );
        }
        if let Some(prev) = slot[part.shard - 1].replace(k) {
            bail!(
                "{}: shard {} given twice (also {})",
                p.display(),
                part.shard,
                parts[prev].0.display()
            );
        }
    }
    if let Some(missing) = slot.iter().position(Option::is_none) {
        bail!("merge: shard {}/{n} is missing", missing + 1);
    }
    let order: Vec<usize> = slot.into_iter().flatten().collect();
    let mut out = Vec::new();
    for [stem, _] in &head.scenarios {
        // Shard order is epoch order within a scenario.
        let pieces: Vec<(&std::path::PathBuf, &Piece)> = order
            .iter()
            .flat_map(|&k| {
                let (p, part) = &parts[k];
                part.pieces
                    .iter()
                    .filter(move |x| &x.meta.name == stem)
                    .map(move |x| (p, x))
            })
            .collect();
        let Some((_, p0)) = pieces.first() else {
            bail!("merge: scenario `{stem}` has no piece");
        };
        if let Some((p, _)) = pieces.iter().find(|(_, x)| x.meta != p0.meta) {
            bail!(
                "{}: scenario `{stem}` differs from the other shards' (run file or users)",
                p.display()
            );
        }
        let users = (0..p0.meta.users.len())
            .map(|u| {
                let mut acc = UserPartial::default();
                for (_, piece) in &pieces {
                    acc.extend(&UserPartial::from(&piece.users[u]));
                }
                acc.summary()
            })
            .collect();
        out.push((p0.meta.clone(), users));
    }
    Ok((head.clone(), out))
}

/// The area-weighted mean availability.
pub fn mean_availability(meta: &Meta, users: &[UserSummary]) -> f64 {
    let wsum: f64 = meta.users.iter().map(|u| u.3).sum();
    meta.users
        .iter()
        .zip(users)
        .map(|(m, u)| m.3 * u.availability)
        .sum::<f64>()
        / wsum
}

/// The coverage-per-scenario table of a sweep, as CSV and markdown: per
/// scenario its stem, the satellite an outage removed, the coverage at
/// each level, the area-weighted mean availability, and the users less
/// and more available than in the first scenario (the run as written).
pub fn sweep_tables(
    head: &SweepHead,
    results: &[ScenarioResult],
    levels: &[f64],
) -> (String, String) {
    let mut csv = format!(
        "scenario,removed,{},mean_availability,users_less_available,users_more_available\n",
        levels
            .iter()
            .map(|l| format!("coverage_{l}"))
            .collect::<Vec<_>>()
            .join(",")
    );
    let mut md = format!(
        "| scenario | removed | {} | mean availability | users less available | users more available |\n| --- | --- |{} ---: | ---: | ---: |\n",
        levels
            .iter()
            .map(|l| format!("coverage at {} %", l * 100.0))
            .collect::<Vec<_>>()
            .join(" | "),
        " ---: |".repeat(levels.len())
    );
    let base: Vec<f64> = results
        .first()
        .map(|(_, u)| u.iter().map(|x| x.availability).collect())
        .unwrap_or_default();
    for ([stem, removed], (meta, users)) in head.scenarios.iter().zip(results) {
        let less = users
            .iter()
            .zip(&base)
            .filter(|(a, b)| a.availability < **b)
            .count();
        let more = users
            .iter()
            .zip(&base)
            .filter(|(a, b)| a.availability > **b)
            .count();
        let mean = mean_availability(meta, users);
        let cov: Vec<f64> = levels.iter().map(|l| coverage(meta, users, *l)).collect();
        let _ = writeln!(
            csv,
            "{stem},{removed},{},{mean:.6},{less},{more}",
            cov.iter()
                .map(|c| format!("{c:.6}"))
                .collect::<Vec<_>>()
                .join(",")
        );
        let _ = writeln!(
            md,
            "| {stem} | {removed} | {} | {:.3} % | {less} | {more} |",
            cov.iter()
                .map(|c| format!("{:.2} %", c * 100.0))
                .collect::<Vec<_>>()
                .join(" | "),
            mean * 100.0
        );
    }
    (csv, md)
}

/// Area-weighted coverage at `level`: sum of the weights of the users with
/// availability >= level over the sum of all weights.
pub fn coverage(meta: &Meta, users: &[UserSummary], level: f64) -> f64 {
    let (mut met, mut all) = (0.0, 0.0);
    for ((_, _, _, w), s) in meta.users.iter().zip(users) {
        all += w;
        if s.availability >= level {
            met += w;
        }
    }
    met / all
}

/// JSON number or null (for +inf and NaN).
fn num(x: f64) -> serde_json::Value {
    serde_json::Number::from_f64(x).map_or(serde_json::Value::Null, serde_json::Value::Number)
}

/// The JSON summary (deterministic: no timing, no host).
pub fn summary_json(meta: &Meta, users: &[UserSummary], levels: &[f64]) -> String {
    let epochs: u64 = users.iter().map(|u| u64::from(u.epochs)).sum();
    let refused: u64 = users.iter().map(|u| u64::from(u.refused)).sum();
    let mean_avail = mean_availability(meta, users);
    let worst_vpl = users
        .iter()
        .map(|u| u.vpl_pct_m)
        .fold(f64::NEG_INFINITY, f64::max);
    let v = serde_json::json!({
        "name": meta.name,
        "run_digest": meta.run_digest,
        "satellites": meta.satellites,
        "unhealthy_left_out": meta.unhealthy,
        "mask_deg": meta.mask_rad.to_degrees(),
        "val_m": meta.limits_m[0],
        "hal_m": meta.limits_m[1],
        "emt_max_m": meta.limits_m[2],
        "sigma_acc_max_m": meta.limits_m[3],
        "target": meta.target,
        "users": users.len(),
        "epochs_per_user": meta.epochs,
        "user_epochs": epochs,
        "refused_user_epochs": refused,
        "pl_percentile": PERCENTILE,
        "coverage": levels.iter().map(|l| serde_json::json!({
            "level": l, "coverage": num(coverage(meta, users, *l)),
        })).collect::<Vec<_>>(),
        "mean_availability_area_weighted": num(mean_avail),
        "worst_user_vpl_percentile_m": num(worst_vpl),
        "max_modes": users.iter().map(|u| u.max_modes).max().unwrap_or(0),
    });
    let mut v = v;
    if let (true, Some(o)) = (meta.horizontal_only, v.as_object_mut()) {
        o.insert("criteria".into(), "HAL only".into());
    }
    if let (Some(lim), Some(o)) = (meta.adjusted_sigma_acc_max_m, v.as_object_mut()) {
        o.insert("position".into(), "adjusted".into());
        o.insert(
            "adjusted_sigma_acc_max_m".into(),
            lim.iter().map(|&x| num(x)).collect::<Vec<_>>().into(),
        );
    }
    if let (Some([phmi, p_fa]), Some(o)) = (meta.budgets, v.as_object_mut()) {
        o.insert("phmi".into(), num(phmi));
        o.insert("p_fa".into(), num(p_fa));
    }
    if let (Some(gaps), Some(o)) = (&meta.ephemeris_gaps, v.as_object_mut()) {
        o.insert(
            "satellite_epochs_without_ephemeris".into(),
            gaps.iter().map(|g| g.1).sum::<usize>().into(),
        );
        o.insert(
            "ephemeris_gaps_epochs".into(),
            gaps.iter()
                .map(|(id, n)| (id.clone(), serde_json::Value::from(*n)))
                .collect::<serde_json::Map<_, _>>()
                .into(),
        );
    }
    let mut s = serde_json::to_string_pretty(&v).unwrap_or_default();
    s.push('\n');
    s
}

/// The per-user CSV.
pub fn users_csv(meta: &Meta, users: &[UserSummary]) -> String {
    let mut s = String::from(
        "name,lat_deg,lon_deg,weight,epochs,available,availability,vpl_p995_m,hpl_p995_m,emt_p995_m,max_modes,refused\n",
    );
    for ((name, lat, lon, w), u) in meta.users.iter().zip(users) {
        let _ = writeln!(
            s,
            "{name},{lat},{lon},{w},{},{},{},{},{},{},{},{}",
            u.epochs,
            u.available,
            u.availability,
            u.vpl_pct_m,
            u.hpl_pct_m,
            u.emt_pct_m,
            u.max_modes,
            u.refused
        );
    }
    s
}

/// Writes `<dir>/<name>.summary.json` and `<dir>/<name>.users.csv`; returns
/// their paths.
///
/// # Errors
/// The directory or a file cannot be written.
pub fn write_outputs(
    dir: &Path,
    meta: &Meta,
    users: &[UserSummary],
    levels: &[f64],
) -> Result<[std::path::PathBuf; 2]> {
    std::fs::create_dir_all(dir).with_context(|| dir.display().to_string())?;
    let json = dir.join(format!("{}.summary.json", meta.name));
    let csv = dir.join(format!("{}.users.csv", meta.name));
    std::fs::write(&json, summary_json(meta, users, levels))
        .with_context(|| json.display().to_string())?;
    std::fs::write(&csv, users_csv(meta, users)).with_context(|| csv.display().to_string())?;
    Ok([json, csv])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shard_ranges_tile_the_epochs() {
        for epochs in [1usize, 7, 288, 289] {
            for n in 1..=9 {
                let mut next = 0;
                for i in 1..=n {
                    let r = shard_range(epochs, i, n);
                    assert_eq!(r.start, next);
                    next = r.end;
                }
                assert_eq!(next, epochs);
            }
        }
        assert_eq!(parse_shard("2/4").unwrap(), (2, 4));
        for bad in ["0/4", "5/4", "x/4", "4", "1/0"] {
            assert!(parse_shard(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn fnv_matches_published_vectors() {
        // FNV-1a 64 test vectors (Fowler/Noll/Vo): "" and "a".
        assert_eq!(fnv1a64(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a64(b"a"), 0xaf63_dc4c_8601_ec8c);
    }
}
