//! Sweeps (docs/AVAILABILITY.md "Sweeps"): the scenarios of one run file.
//!
//! A run file with `[[scenario]]` entries is a sweep: the run as written
//! (the first scenario, `removed` = `none`), then each scenario, the run
//! with what the scenario names overridden (mask, height, exclusion and
//! its continuity budget, service level, the constellations kept, and per
//! constellation any key: almanac, removed and added PRNs, ISM values).
//! The grid and the time span are the run's, so that every scenario has
//! the same users (the table compares them user by user) and the same
//! epochs (shards tile scenario x epoch). A scenario with `outages = SYS`
//! generates every single-satellite outage of constellation SYS of that
//! scenario, by the same function as `raim availability --outages SYS`
//! ([`single_outages`]).

use std::path::Path;

use anyhow::{anyhow, bail, Result};
use raim_core::System;
use serde::Deserialize;
use toml::{Table, Value};

use crate::run::{self, Loc, RunFile, Study};

/// One scenario of a sweep.
#[derive(Debug, Clone)]
pub struct Scenario {
    /// The satellite an outage scenario removed (`G03`), else `none`.
    pub removed: String,
    /// The study; its name is the output files' stem.
    pub study: Study,
}

/// The scenarios of one run.
#[derive(Debug, Clone)]
pub struct Sweep {
    /// The run's name.
    pub name: String,
    /// The coverage table's file tag (`<name>.<tag>.csv` and `.md`):
    /// `outages` for `--outages`, `sweep` for `[[scenario]]`; none for a
    /// single run.
    pub table: Option<String>,
    /// The scenarios, the run as written first.
    pub scenarios: Vec<Scenario>,
}

/// The keys a scenario may set besides `name`, `outages`, `systems` and
/// `constellation`: each replaces the run's.
pub const REPLACED: [&str; 5] = ["mask_deg", "height_m", "exclusion", "continuity", "service"];

/// `G` or `E`.
///
/// # Errors
/// Another letter.
pub fn parse_system(s: &str) -> Result<System> {
    match s {
        "G" => Ok(System::Gps),
        "E" => Ok(System::Galileo),
        s => Err(anyhow!("constellation `{s}`: G or E")),
    }
}

/// Every single-satellite outage of `system` in `study`: one study per
/// satellite of that system with it removed, named
/// `<study name>.outage-<sat>`.
pub fn single_outages(study: &Study, system: System) -> Vec<Scenario> {
    study
        .sats
        .iter()
        .filter(|s| s.id.system == system)
        .map(|s| {
            let label = format!("{}{:02}", system.letter(), s.id.prn);
            let mut o = study.clone();
            let (sats, ism): (Vec<_>, Vec<_>) = study
                .sats
                .iter()
                .zip(&study.ism_entries)
                .filter(|(x, _)| x.id != s.id)
                .map(|(x, i)| (x.clone(), *i))
                .unzip();
            o.sats = sats;
            o.ism_entries = ism;
            o.name = format!("{}.outage-{label}", study.name);
            Scenario {
                removed: label,
                study: o,
            }
        })
        .collect()
}

/// `raim availability --outages SYS`: the run as written and every
/// single-satellite outage of SYS (not with `[[scenario]]`).
///
/// # Errors
/// As [`run::load`]; a run file with scenarios; SYS not G or E or with no
/// satellite in the run.
pub fn load_outages(path: &Path, sys: &str) -> Result<Sweep> {
    let text = std::fs::read_to_string(path).map_err(|e| anyhow!("{}: {e}", path.display()))?;
    let file: RunFile = run::parse(&text, path)?;
    if !file.scenario.is_empty() {
        bail!(
            "{}: --outages sweeps the run as written; this file has [[scenario]] entries \
             (write `outages = \"{sys}\"` in a scenario instead)",
            path.display()
        );
    }
    let study = run::build(
        &file,
        &Loc::base(&text, path),
        path.parent().unwrap_or(Path::new(".")),
    )?;
    let system = parse_system(sys).map_err(|e| anyhow!("--outages: {e}"))?;
    let outages = single_outages(&study, system);
    if outages.is_empty() {
        bail!("--outages {sys}: the run has no satellite of {sys}");
    }
    let mut scenarios = vec![Scenario {
        removed: "none".into(),
        study,
    }];
    scenarios.extend(outages);
    Ok(Sweep {
        name: scenarios[0].study.name.clone(),
        table: Some("outages".into()),
        scenarios,
    })
}

/// Reads a run file: one scenario, or the run as written and its
/// `[[scenario]]` entries (each expanded by its outage generator).
///
/// # Errors
/// As [`run::load`], for the run and for each scenario (named, with the
/// scenario's lines); a scenario without a name, with a name given twice,
/// with a key it cannot set, or an outage generator with no satellite.
pub fn load(path: &Path) -> Result<Sweep> {
    let text = std::fs::read_to_string(path).map_err(|e| anyhow!("{}: {e}", path.display()))?;
    from_text(&text, path, path.parent().unwrap_or(Path::new(".")))
}

/// [`load`] on text in memory (almanac paths relative to `base`).
///
/// # Errors
/// As [`load`].
pub fn from_text(text: &str, path: &Path, base: &Path) -> Result<Sweep> {
    let file: RunFile = run::parse(text, path)?;
    let study = run::build(&file, &Loc::base(text, path), base)?;
    let name = study.name.clone();
    let mut scenarios = vec![Scenario {
        removed: "none".into(),
        study,
    }];
    if file.scenario.is_empty() {
        return Ok(Sweep {
            name,
            table: None,
            scenarios,
        });
    }
    let mut written: Table = run::parse(text, path)?;
    written.remove("scenario");
    // Each `[[scenario]]` header opens that scenario's lines.
    let starts: Vec<usize> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| l.trim() == "[[scenario]]")
        .map(|(i, _)| i)
        .collect();
    for (k, sc) in file.scenario.iter().enumerate() {
        let lines = if starts.len() == file.scenario.len() {
            starts[k]..starts.get(k + 1).copied().unwrap_or(usize::MAX)
        } else {
            0..usize::MAX
        };
        let loc = Loc::within(text, path, lines);
        let (label, outages, merged) = merge(&written, sc, &name, &loc)?;
        let wrap = |e: anyhow::Error| anyhow!("scenario `{label}`: {e}");
        let r = RunFile::deserialize(Value::Table(merged))
            .map_err(|e| anyhow!("{}: {e}", loc.at("name")))
            .map_err(wrap)?;
        let s = run::build(&r, &loc, base).map_err(wrap)?;
        match outages {
            None => scenarios.push(Scenario {
                removed: "none".into(),
                study: s,
            }),
            Some(sys) => {
                let system = parse_system(&sys)
                    .map_err(|e| anyhow!("{}: outages: {e}", loc.at("outages")))
                    .map_err(wrap)?;
                let o = single_outages(&s, system);
                if o.is_empty() {
                    return Err(wrap(anyhow!(
                        "{}: outages = \"{sys}\": the scenario has no satellite of {sys}",
                        loc.at("outages")
                    )));
                }
                scenarios.extend(o);
            }
        }
    }
    let mut names: Vec<&str> = scenarios.iter().map(|s| s.study.name.as_str()).collect();
    names.sort_unstable();
    if let Some(w) = names.windows(2).find(|w| w[0] == w[1]) {
        bail!("{}: two scenarios are named `{}`", path.display(), w[0]);
    }
    Ok(Sweep {
        name,
        table: Some("sweep".into()),
        scenarios,
    })
}

/// The run as written with scenario `sc` applied: its label, its outage
/// generator, and the merged run (named `<run>.<label>`).
fn merge(
    written: &Table,
    sc: &Table,
    run_name: &str,
    loc: &Loc<'_>,
) -> Result<(String, Option<String>, Table)> {
    let label = match sc.get("name") {
        Some(Value::String(s))
            if !s.is_empty()
                && s
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.')) =>
        {
            s.clone()
        }
        _ => bail!(
            "{}: a [[scenario]] needs `name`, of letters, digits, '-', '_' and '.' (the output files' stem)",
            loc.at("name")
        ),
    };
    let fail = |key: &str, what: String| anyhow!("{}: scenario `{label}`: {what}", loc.at(key));
    let mut t = written.clone();
    // A scenario that sets detection only drops the continuity budget the
    // run as written carries for its exclusion rule.
    if let Some(Value::String(e)) = sc.get("exclusion") {
        if e != "continuity" {
            t.remove("continuity");
            if let Some(Value::Array(cs)) = t.get_mut("constellation") {
                for c in cs.iter_mut().filter_map(Value::as_table_mut) {
                    c.remove("mfd_sat_s");
                    c.remove("mfd_const_s");
                }
            }
        }
    }
    let mut outages = None;
    for (k, v) in sc {
        match k.as_str() {
            "name" | "constellation" | "systems" => {}
            "outages" => {
                outages = Some(
                    v.as_str()
                        .ok_or_else(|| fail("outages", "outages = \"G\" or \"E\"".into()))?
                        .to_string(),
                );
            }
            k if REPLACED.contains(&k) => {
                t.insert(k.to_string(), v.clone());
            }
            k => {
                return Err(fail(
                    k,
                    format!(
                        "`{k}` cannot be set in a scenario (it sets {}, systems, constellation, \
                         outages; the grid and the time span are the run's)",
                        REPLACED.join(", ")
                    ),
                ))
            }
        }
    }
    let system_of = |c: &Value| c.get("system").and_then(Value::as_str).map(str::to_string);
    let mut cs: Vec<Value> = match t.remove("constellation") {
        Some(Value::Array(a)) => a,
        _ => Vec::new(),
    };
    if let Some(v) = sc.get("systems") {
        let keep: Vec<String> = v
            .as_array()
            .map(|a| {
                a.iter()
                    .filter_map(|x| x.as_str().map(str::to_string))
                    .collect()
            })
            .unwrap_or_default();
        if keep.is_empty() {
            return Err(fail(
                "systems",
                "systems = [\"G\", ...]: a non-empty list".into(),
            ));
        }
        for s in &keep {
            if !cs
                .iter()
                .any(|c| system_of(c).as_deref() == Some(s.as_str()))
            {
                return Err(fail(
                    "systems",
                    format!("systems lists `{s}`, which the run has no constellation of"),
                ));
            }
        }
        cs.retain(|c| system_of(c).is_some_and(|s| keep.contains(&s)));
    }
    if let Some(over) = sc.get("constellation") {
        let over = over.as_array().ok_or_else(|| {
            fail(
                "constellation",
                "[[scenario.constellation]] tables expected".into(),
            )
        })?;
        for o in over {
            let (Some(ot), Some(sys)) = (o.as_table(), system_of(o)) else {
                return Err(fail(
                    "system",
                    "each [[scenario.constellation]] names its `system`".into(),
                ));
            };
            match cs
                .iter_mut()
                .filter_map(Value::as_table_mut)
                .find(|c| c.get("system").and_then(Value::as_str) == Some(sys.as_str()))
            {
                Some(c) => {
                    for (k, v) in ot {
                        c.insert(k.clone(), v.clone());
                    }
                }
                None => cs.push(o.clone()),
            }
        }
    }
    t.insert("constellation".into(), Value::Array(cs));
    t.insert("name".into(), Value::String(format!("{run_name}.{label}")));
    Ok((label, outages, t))
}
