//! `raim pci`: probability of correct identification per satellite for MLE
//! and L-RAIM fault identification, exact (d <= 3) and Monte Carlo, with the
//! detection probability and the minimal detectable bias (SPEC §4.3).
//!
//! Model: H = [-LOS(ENU), 1] (one clock per constellation), sigma = 1, so
//! biases are in sigma units. P_CI is unconditional (the rule is applied to
//! every draw, detected or not); P(CI | D) is conditional on the chi-square
//! test alarming.

pub mod design;
pub mod exact;
pub mod geometry;
pub mod montecarlo;
pub mod plot;
pub mod report;
pub mod rules;

use std::io::Read;

use anyhow::{bail, Context, Result};
use clap::Args;
use raim_core::config::DEFAULT_KAPPA;

use crate::epoch_json::EpochJson;
use design::DesignKind;
use geometry::{Geometry, Sat};
use report::{PciReport, RuleCell, SatRow};

/// `raim pci` arguments.
#[derive(Debug, Args)]
pub struct PciArgs {
    /// Azimuths, degrees (comma separated). Without --az/--el a JSON epoch
    /// (linearised form, docs/FORMATS.md) is read from stdin.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub az: Vec<f64>,
    /// Elevations, degrees (comma separated).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub el: Vec<f64>,
    /// Probability of false alarm of the chi-square test.
    #[arg(long, default_value = "1e-3")]
    pub pfa: f64,
    /// Target detection probability (sets the biases, see --design).
    #[arg(long, conflicts_with = "bias")]
    pub pd: Option<f64>,
    /// One bias for every satellite, sigma units.
    #[arg(long)]
    pub bias: Option<f64>,
    /// With --pd: pd-matched (each satellite gets the bias that gives the
    /// chi-square test P_D) or fixed-b (one bias for every satellite: given,
    /// or chosen so the mean P_D is the target).
    #[arg(long, value_enum, default_value_t = DesignKind::PdMatched)]
    pub design: DesignKind,
    /// Prior variance ratio of Gaussian L-RAIM (tau^2 / sigma^2).
    #[arg(long, default_value_t = DEFAULT_KAPPA)]
    pub kappa: f64,
    /// Missed-detection probability for the MDB.
    #[arg(long, default_value = "1e-3")]
    pub pmd: f64,
    /// Smallest identifiable S_ii (the core's default).
    #[arg(long, default_value = "1e-4")]
    pub min_s_ii: f64,
    /// Monte Carlo draws (0: none; exact only, d <= 3).
    #[arg(long, default_value_t = 200_000)]
    pub mc: usize,
    /// Monte Carlo seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Skip the exact integration.
    #[arg(long)]
    pub no_exact: bool,
    /// Print JSON instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Write a PNG of P_CI against bias for each satellite and rule.
    #[arg(long)]
    pub plot: Option<std::path::PathBuf>,
    /// TrueType font for the plot's text (default: DejaVu Sans if installed).
    #[arg(long)]
    pub font: Option<std::path::PathBuf>,
}

/// The satellites from --az/--el, or from a JSON epoch on stdin.
fn read_sats(args: &PciArgs) -> Result<Vec<Sat>> {
    if !args.az.is_empty() || !args.el.is_empty() {
        return geometry::sats_from_lists(&args.az, &args.el);
    }
    let mut text = String::new();
    std::io::stdin()
        .read_to_string(&mut text)
        .context("reading the epoch from stdin")?;
    let line = text
        .lines()
        .find(|l| !l.trim().is_empty() && !l.trim_start().starts_with('#'))
        .context("no --az/--el and no epoch on stdin")?;
    let epoch: EpochJson =
        serde_json::from_str(line).context("stdin: not an epoch (docs/FORMATS.md)")?;
    epoch_sats(&epoch)
}

/// Satellites of a linearised-form epoch (residuals are ignored).
pub fn epoch_sats(epoch: &EpochJson) -> Result<Vec<Sat>> {
    match epoch.to_sats()? {
        crate::epoch_json::Sats::Linear(v) => Ok(v
            .iter()
            .zip(epoch.sats.iter())
            .map(|(o, s)| Sat {
                id: o.id,
                az_deg: s.az_deg.unwrap_or(f64::NAN),
                el_deg: s.el_deg.unwrap_or(f64::NAN),
                los_enu: o.los_enu,
            })
            .collect()),
        crate::epoch_json::Sats::Ranges(_) => {
            bail!("raim pci needs the linearised form (az_deg, el_deg)")
        }
    }
}

/// Everything `raim pci` computes, for a geometry and options.
pub fn analyse(geom: &Geometry, args: &PciArgs) -> Result<PciReport> {
    if !(args.pfa > 0.0 && args.pfa < 0.5) {
        bail!("--pfa must be in (0, 0.5), got {}", args.pfa);
    }
    if !(args.pmd > 0.0 && args.pmd < 0.5) {
        bail!("--pmd must be in (0, 0.5), got {}", args.pmd);
    }
    if !(args.kappa > 0.0 && args.kappa.is_finite()) {
        bail!("--kappa must be positive, got {}", args.kappa);
    }
    let rules = rules::rules(args.kappa);
    let t2 = design::threshold(args.pfa, geom.d)?;
    let design = if args.bias.is_some() {
        DesignKind::FixedB
    } else {
        args.design
    };
    let bias = design::biases(
        geom,
        t2,
        args.pfa,
        design,
        args.pd,
        args.bias,
        args.min_s_ii,
    )?;
    let mdb = design::mdb(geom, args.pfa, args.pmd, args.min_s_ii)?;
    let mc_bias: Vec<f64> = bias
        .iter()
        .map(|b| if b.is_finite() { *b } else { 0.0 })
        .collect();
    let mc = if args.mc > 0 {
        let spec = montecarlo::McSpec {
            draws: args.mc,
            seed: args.seed,
            progress: !args.json,
        };
        Some(montecarlo::run(
            geom,
            &rules,
            args.min_s_ii,
            &mc_bias,
            t2,
            spec,
        ))
    } else {
        None
    };
    let do_exact = !args.no_exact && (1..=3).contains(&geom.d);
    let mut sats = Vec::new();
    for i in 0..geom.n() {
        let lambda = mc_bias[i] * mc_bias[i] * geom.s_ii[i];
        let pd = design::p_detect(t2, geom.d, lambda)?;
        let mut cells = Vec::new();
        for (r, rule) in rules.iter().enumerate() {
            let ex = if do_exact {
                Some(exact::p_ci(
                    geom,
                    rule.rule,
                    args.min_s_ii,
                    i,
                    mc_bias[i],
                    t2,
                )?)
            } else {
                None
            };
            cells.push(RuleCell::new(
                rule.name,
                ex,
                pd,
                mc.as_ref().map(|m| m.cells[i][r]),
            ));
        }
        sats.push(SatRow {
            sat: geom.sats[i].id.to_string(),
            az_deg: geom.sats[i].az_deg,
            el_deg: geom.sats[i].el_deg,
            s_ii: geom.s_ii[i],
            h_ii: geom.h_ii(i),
            bias: bias[i],
            lambda,
            p_d: pd,
            p_d_mc: mc.as_ref().map(|m| m.p_d[i]),
            p_d_mc_se: mc.as_ref().map(|m| m.p_d_se[i]),
            mdb: mdb[i],
            rules: cells,
        });
    }
    Ok(PciReport::new(geom, args, design, t2, mc.as_ref(), sats))
}

/// `raim pci`.
pub fn run(args: &PciArgs) -> Result<()> {
    let geom = Geometry::new(read_sats(args)?)?;
    let rep = analyse(&geom, args)?;
    if args.json {
        crate::outln!("{}", serde_json::to_string_pretty(&rep)?)?;
    } else {
        crate::out!("{}", rep.table())?;
    }
    if let Some(path) = &args.plot {
        plot::pci_vs_bias(&geom, args, path)?;
        if !args.json {
            crate::outln!("plot: {}", path.display())?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Wrap {
        #[command(flatten)]
        args: PciArgs,
    }

    fn args(extra: &[&str]) -> PciArgs {
        let mut v = vec!["pci"];
        v.extend_from_slice(extra);
        Wrap::parse_from(v).args
    }

    /// pd-matched: every satellite at the target P_D; fixed-b: one bias with
    /// mean P_D at the target; averages are the means of the rows; MDB
    /// follows sqrt(lambda / S_ii) with lambda from `raim threshold`'s dist.
    #[test]
    fn designs_and_averages() {
        let g = geometry::fixtures::beidou();
        const PD_TOL: f64 = 1e-9; // probability
        let a = args(&["--pfa", "1e-3", "--pd", "0.9", "--mc", "0"]);
        let r = analyse(&g, &a).unwrap();
        for s in &r.sats {
            assert!((s.p_d - 0.9).abs() < PD_TOL, "{}", s.p_d);
            assert!((s.lambda - r.sats[0].lambda).abs() < 1e-9);
        }
        let lambda_md = raim_core::stats::dist::ncx2_lambda(1e-3, 1e-3, 2).unwrap();
        for (s, &sii) in r.sats.iter().zip(g.s_ii.iter()) {
            assert!((s.mdb - (lambda_md / sii).sqrt()).abs() < 1e-9);
        }
        for (k, avg) in r.average.iter().enumerate() {
            let m: f64 = r
                .sats
                .iter()
                .map(|s| s.rules[k].p_ci_exact.unwrap())
                .sum::<f64>()
                / 6.0;
            assert!((avg.p_ci.unwrap() - m).abs() < 1e-15);
        }
        let f = analyse(
            &g,
            &args(&[
                "--pfa", "1e-3", "--pd", "0.9", "--design", "fixed-b", "--mc", "0",
            ]),
        )
        .unwrap();
        assert!((f.mean_p_d - 0.9).abs() < PD_TOL);
        assert!(f.sats.iter().all(|s| s.bias == f.sats[0].bias));
        // JSON carries the same numbers.
        let j = serde_json::to_value(&f).unwrap();
        assert_eq!(j["sats"][0]["rules"][1]["rule"], "lraim_flat");
        assert_eq!(j["sats"][0]["bias"].as_f64().unwrap(), f.sats[0].bias);
    }

    #[test]
    fn bad_options_are_errors() {
        let g = geometry::fixtures::beidou();
        assert!(analyse(&g, &args(&["--pfa", "0.7", "--pd", "0.9"])).is_err());
        assert!(analyse(&g, &args(&["--pd", "1e-4"])).is_err());
        assert!(analyse(&g, &args(&["--bias=-1"])).is_err());
        assert!(analyse(&g, &args(&["--kappa", "0", "--bias", "3"])).is_err());
        assert!(
            analyse(&g, &args(&["--mc", "0"])).is_err(),
            "neither --pd nor --bias"
        );
    }

    /// A JSON epoch (linearised form) gives the same geometry as --az/--el.
    #[test]
    fn epoch_json_geometry() {
        let text = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../docs/lraim/beidou_table1.json"
        ))
        .unwrap();
        let e: EpochJson = serde_json::from_str(&text).unwrap();
        let g = Geometry::new(epoch_sats(&e).unwrap()).unwrap();
        let h = geometry::fixtures::beidou();
        for (a, b) in g.s_ii.iter().zip(h.s_ii.iter()) {
            assert!((a - b).abs() < 1e-12);
        }
        assert_eq!(g.sats[0].id.to_string(), "C05");
    }
}
