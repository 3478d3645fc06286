//! `raim araim`: ARAIM (docs/ARAIM.md) on epochs in the ARAIM epoch format
//! of docs/FORMATS.md, one JSON object per line; prints one result per epoch.

use std::io::{BufRead, Write};

use anyhow::{anyhow, bail, Context, Result};
use raim_core::araim::{
    AraimConfig, AraimOutput, AraimSat, Exclusion, FdeLimits, Ism, ModeStatus, Monitor,
    MonitorError, Verdict,
};
use raim_core::{SatId, System};
use serde_json::{json, Value};

/// Satellites and fault modes of the host engine.
const N: usize = 32;
const K: usize = 2048;

#[derive(clap::Args)]
pub struct AraimArgs {
    /// Print one JSON object per line instead of text.
    #[arg(long)]
    json: bool,
    /// Read from this file instead of stdin.
    #[arg(long)]
    input: Option<std::path::PathBuf>,
    /// Include the per-mode table in the JSON output.
    #[arg(long)]
    modes: bool,
}

fn num(v: &Value, key: &str) -> Result<f64> {
    v.get(key)
        .and_then(Value::as_f64)
        .ok_or_else(|| anyhow!("missing number `{key}`"))
}

fn system(letter: &str) -> Result<System> {
    letter
        .chars()
        .next()
        .and_then(System::from_letter)
        .ok_or_else(|| anyhow!("unknown system `{letter}`"))
}

/// Parses one ARAIM epoch.
pub fn parse_epoch(v: &Value) -> Result<(f64, AraimConfig, Ism, Vec<AraimSat<f64>>)> {
    let time_s = v.get("time_s").and_then(Value::as_f64).unwrap_or(0.0);
    let mut cfg = AraimConfig::default();
    if let Some(c) = v.get("araim_config") {
        for (key, slot) in [
            ("phmi_vert", &mut cfg.phmi_vert),
            ("phmi_hor", &mut cfg.phmi_hor),
            ("pfa_vert", &mut cfg.pfa_vert),
            ("pfa_hor", &mut cfg.pfa_hor),
            ("p_thres", &mut cfg.p_thres),
            ("p_emt", &mut cfg.p_emt),
            ("val_m", &mut cfg.val_m),
            ("hal_m", &mut cfg.hal_m),
            ("tol_pl_m", &mut cfg.tol_pl_m),
        ] {
            if let Some(x) = c.get(key).and_then(Value::as_f64) {
                *slot = x;
            }
        }
    }
    let mut ism = Ism::default();
    let p_const = v
        .get("ism")
        .and_then(|i| i.get("p_const"))
        .and_then(Value::as_object)
        .ok_or_else(|| anyhow!("missing `ism.p_const`"))?;
    for (letter, p) in p_const {
        let s = system(letter)?;
        ism.p_const[s.index()] = Some(p.as_f64().ok_or_else(|| anyhow!("p_const of {letter}"))?);
    }
    let mut sats = Vec::new();
    for (i, s) in v
        .get("sats")
        .and_then(Value::as_array)
        .ok_or_else(|| anyhow!("missing `sats`"))?
        .iter()
        .enumerate()
    {
        let g: Vec<f64> = s
            .get("g_enu")
            .and_then(Value::as_array)
            .map(|a| a.iter().filter_map(Value::as_f64).collect())
            .unwrap_or_default();
        if g.len() != 3 {
            bail!("satellite {i}: `g_enu` must be 3 numbers");
        }
        sats.push(AraimSat {
            id: SatId {
                system: system(s.get("sys").and_then(Value::as_str).unwrap_or(""))?,
                prn: s
                    .get("prn")
                    .and_then(Value::as_u64)
                    .and_then(|p| u8::try_from(p).ok())
                    .ok_or_else(|| anyhow!("satellite {i}: `prn`"))?,
            },
            g_enu: [g[0], g[1], g[2]],
            c_int_m2: num(s, "c_int_m2").with_context(|| format!("satellite {i}"))?,
            c_acc_m2: num(s, "c_acc_m2").with_context(|| format!("satellite {i}"))?,
            b_nom_m: num(s, "b_nom_m").with_context(|| format!("satellite {i}"))?,
            p_sat: num(s, "p_sat").with_context(|| format!("satellite {i}"))?,
            residual_m: s.get("residual_m").and_then(Value::as_f64).unwrap_or(0.0),
        });
    }
    Ok((time_s, cfg, ism, sats))
}

fn sat_name(s: &AraimSat<f64>) -> String {
    format!("{}{:02}", s.id.system.letter(), s.id.prn)
}

fn mode_json(sats: &[AraimSat<f64>], out: &AraimOutput<f64, K>) -> Vec<Value> {
    out.modes
        .iter()
        .map(|m| {
            let names: Vec<String> = sats
                .iter()
                .enumerate()
                .filter(|(i, _)| m.events.sats & (1u64 << i) != 0)
                .map(|(_, s)| sat_name(s))
                .collect();
            let consts: Vec<String> = System::ALL
                .iter()
                .filter(|s| m.events.consts & (1u8 << s.index()) != 0)
                .map(|s| s.letter().to_string())
                .collect();
            json!({
                "sats": names, "constellations": consts, "prior": m.events.prior,
                "monitored": m.status == ModeStatus::Monitored,
                "sigma_m": m.stats.sigma_m, "bias_m": m.stats.bias_m,
                "sigma_ss_m": m.stats.sigma_ss_m, "threshold_m": m.threshold_m,
                "separation_m": m.stats.separation_m, "passed": m.passed,
            })
        })
        .collect()
}

/// The exclusion outcome as printed: the FDE's decision, or why none ran
/// (the names of `raim replay --araim`'s `fde`, with the mode indices).
fn fde_text(e: &Exclusion) -> String {
    use raim_core::araim::{FdeAlarm, FdeDecision};
    match e {
        Exclusion::Fde(FdeDecision::NoFault) => "no_fault".into(),
        Exclusion::Fde(FdeDecision::Excluded { mode, .. }) => format!("excluded (mode {mode})"),
        Exclusion::Fde(FdeDecision::Alarm(FdeAlarm::NoCandidate)) => "alarm_no_candidate".into(),
        Exclusion::Fde(FdeDecision::Alarm(FdeAlarm::Ambiguous { first, second })) => {
            format!("alarm_ambiguous (modes {first} and {second})")
        }
        Exclusion::Fde(FdeDecision::Alarm(FdeAlarm::BudgetExceeded { candidates, budget })) => {
            format!("alarm_budget_exceeded ({candidates} candidates, budget {budget})")
        }
        Exclusion::NotTested => "not_tested".into(),
        Exclusion::NotAttempted { monitored } => {
            format!("alarm_not_attempted ({monitored} monitored modes)")
        }
    }
}

fn result_json(
    time_s: f64,
    sats: &[AraimSat<f64>],
    out: &AraimOutput<f64, K>,
    verdict: &Verdict<N>,
    with_modes: bool,
) -> Value {
    let excluded: Vec<String> = verdict
        .excluded
        .iter()
        .map(|id| format!("{}{:02}", id.system.letter(), id.prn))
        .collect();
    let fde = fde_text(&verdict.exclusion);
    let mut v = json!({
        "time_s": time_s,
        "available": out.available(),
        "unavailable": out.unavailable.map(|u| crate::replay::araim::unavailable_name(&u.into())),
        "modes": out.modes.len(), "monitored": out.n_monitored,
        "max_faults": out.max_faults, "p_unmon": out.p_unmon, "k_fa": out.k_fa,
        "vpl_m": out.pl_add.vpl_m, "hpl_m": out.pl_add.hpl_m,
        "vpl_exact_m": out.pl_exact.vpl_m, "hpl_exact_m": out.pl_exact.hpl_m,
        "hpl_axes_exact_m": out.pl_exact.hpl_axes_m,
        "emt_m": out.emt_m, "sigma_v_acc_m": out.sigma_v_acc_m,
        "sigma_enu_m": out.sigma0_m, "correction_enu_m": out.correction_enu_m,
        "detection_passed": out.detection_passed,
        "fde": fde, "excluded": excluded,
    });
    if with_modes {
        v["mode_table"] = Value::Array(mode_json(sats, out));
    }
    v
}

pub fn run(args: &AraimArgs) -> Result<()> {
    let reader: Box<dyn BufRead> = match &args.input {
        Some(p) => Box::new(std::io::BufReader::new(
            std::fs::File::open(p).with_context(|| format!("opening {}", p.display()))?,
        )),
        None => Box::new(std::io::stdin().lock()),
    };
    let mut monitor = Box::new(Monitor::<f64, N, K>::new());
    let stdout = std::io::stdout();
    let mut w = stdout.lock();
    for (lineno, line) in reader.lines().enumerate() {
        let line = line?;
        if line.trim().is_empty() || line.trim_start().starts_with('#') {
            continue;
        }
        let v: Value = serde_json::from_str(&line)
            .with_context(|| format!("line {}: not JSON", lineno + 1))?;
        let (time_s, cfg, ism, sats) =
            parse_epoch(&v).with_context(|| format!("line {}", lineno + 1))?;
        match monitor.given(&cfg, &ism, &sats, FdeLimits::UNLIMITED) {
            Ok(verdict) => {
                let out = monitor.all_in_view();
                let fde = fde_text(&verdict.exclusion);
                if args.json {
                    let v = result_json(time_s, &sats, out, &verdict, args.modes);
                    writeln!(w, "{}", serde_json::to_string(&v)?)?;
                } else {
                    writeln!(
                        w,
                        "t={time_s:>10.1}s modes {:>4} VPL {:7.3} m HPL {:7.3} m EMT {:6.3} m sigma_v,acc {:5.3} m {} {fde}",
                        out.modes.len(),
                        out.pl_add.vpl_m,
                        out.pl_add.hpl_m,
                        out.emt_m,
                        out.sigma_v_acc_m,
                        if out.available() { "available" } else { "UNAVAILABLE" },
                    )?;
                }
            }
            Err(e) if args.json => {
                // The engine's own error, as before the monitor wrapped it.
                let debug = match e {
                    MonitorError::Araim(a) => format!("{a:?}"),
                    other => format!("{other:?}"),
                };
                writeln!(
                    w,
                    "{}",
                    serde_json::to_string(
                        &json!({"time_s": time_s, "error": debug, "detail": e.to_string()})
                    )?
                )?
            }
            Err(e) => writeln!(w, "t={time_s:>10.1}s ERROR {e}")?,
        }
    }
    Ok(())
}
