//! The `raim pci` report: per-satellite rows, averages over satellites, a
//! readable table and the JSON form (serde).

use std::fmt::Write;

use serde::Serialize;

use super::design::DesignKind;
use super::exact::Exact;
use super::geometry::Geometry;
use super::montecarlo::{McCell, McResult};
use super::PciArgs;

/// One rule's numbers for one satellite.
#[derive(Debug, Clone, Serialize)]
pub struct RuleCell {
    pub rule: &'static str,
    /// Exact P_CI (d <= 3) and its numerical error.
    pub p_ci_exact: Option<f64>,
    pub p_ci_exact_err: Option<f64>,
    /// Exact P(CI | D) = P(CI and D) / P_D.
    pub p_ci_given_d_exact: Option<f64>,
    pub p_ci_mc: Option<f64>,
    pub p_ci_mc_se: Option<f64>,
    pub p_ci_given_d_mc: Option<f64>,
    pub p_ci_given_d_mc_se: Option<f64>,
}

impl RuleCell {
    pub fn new(rule: &'static str, ex: Option<Exact>, p_d: f64, mc: Option<McCell>) -> Self {
        RuleCell {
            rule,
            p_ci_exact: ex.map(|e| e.p_ci),
            p_ci_exact_err: ex.map(|e| e.err),
            p_ci_given_d_exact: ex.map(|e| e.p_ci_and_d / p_d),
            p_ci_mc: mc.map(|m| m.p_ci),
            p_ci_mc_se: mc.map(|m| m.p_ci_se),
            p_ci_given_d_mc: mc.map(|m| m.p_ci_given_d),
            p_ci_given_d_mc_se: mc.map(|m| m.p_ci_given_d_se),
        }
    }

    /// The best available P_CI (exact if computed, else Monte Carlo).
    pub fn p_ci(&self) -> Option<f64> {
        self.p_ci_exact.or(self.p_ci_mc)
    }

    pub fn p_ci_given_d(&self) -> Option<f64> {
        self.p_ci_given_d_exact.or(self.p_ci_given_d_mc)
    }
}

/// One satellite's row.
#[derive(Debug, Clone, Serialize)]
pub struct SatRow {
    pub sat: String,
    pub az_deg: f64,
    pub el_deg: f64,
    pub s_ii: f64,
    pub h_ii: f64,
    /// Bias, sigma units.
    pub bias: f64,
    /// Non-centrality b^2 S_ii.
    pub lambda: f64,
    /// P_D from the non-central chi-square (core's dist).
    pub p_d: f64,
    pub p_d_mc: Option<f64>,
    pub p_d_mc_se: Option<f64>,
    /// Minimal detectable bias for (Pfa, Pmd), sigma units.
    pub mdb: f64,
    pub rules: Vec<RuleCell>,
}

/// Averages over satellites of one rule.
#[derive(Debug, Clone, Serialize)]
pub struct RuleAverage {
    pub rule: &'static str,
    pub p_ci: Option<f64>,
    pub p_ci_given_d: Option<f64>,
    /// Monte Carlo standard error of the average (common random numbers
    /// make the satellites' errors correlated; this is the mean of their
    /// standard errors, an upper bound of the standard error of the mean).
    pub p_ci_mc_se: Option<f64>,
}

#[derive(Debug, Clone, Serialize)]
pub struct McInfo {
    pub draws: usize,
    pub seed: u64,
}

/// Everything `raim pci` reports.
#[derive(Debug, Clone, Serialize)]
pub struct PciReport {
    pub n: usize,
    pub m: usize,
    pub dof: usize,
    pub pfa: f64,
    pub pmd: f64,
    pub threshold_chi2: f64,
    pub design: DesignKind,
    pub target_pd: Option<f64>,
    pub kappa: f64,
    pub min_s_ii: f64,
    pub monte_carlo: Option<McInfo>,
    pub sats: Vec<SatRow>,
    pub average: Vec<RuleAverage>,
    pub mean_p_d: f64,
}

fn mean(v: impl Iterator<Item = Option<f64>>) -> Option<f64> {
    let (mut s, mut k) = (0.0, 0usize);
    for x in v {
        s += x?;
        k += 1;
    }
    (k > 0).then(|| s / k as f64)
}

impl PciReport {
    pub fn new(
        geom: &Geometry,
        args: &PciArgs,
        design: DesignKind,
        t2: f64,
        mc: Option<&McResult>,
        sats: Vec<SatRow>,
    ) -> Self {
        let nr = sats.first().map_or(0, |s| s.rules.len());
        let average = (0..nr)
            .map(|r| RuleAverage {
                rule: sats[0].rules[r].rule,
                p_ci: mean(sats.iter().map(|s| s.rules[r].p_ci())),
                p_ci_given_d: mean(sats.iter().map(|s| s.rules[r].p_ci_given_d())),
                p_ci_mc_se: mean(sats.iter().map(|s| s.rules[r].p_ci_mc_se)),
            })
            .collect();
        let mean_p_d = sats.iter().map(|s| s.p_d).sum::<f64>() / sats.len().max(1) as f64;
        PciReport {
            n: geom.n(),
            m: geom.m,
            dof: geom.d,
            pfa: args.pfa,
            pmd: args.pmd,
            threshold_chi2: t2,
            design,
            target_pd: args.pd,
            kappa: args.kappa,
            min_s_ii: args.min_s_ii,
            monte_carlo: mc.map(|m| McInfo {
                draws: m.draws,
                seed: m.seed,
            }),
            sats,
            average,
            mean_p_d,
        }
    }

    /// The readable table.
    pub fn table(&self) -> String {
        let mut o = String::new();
        let _ = writeln!(
            o,
            "n={} m={} d={} Pfa={:e} T^2={:.4} design={} kappa={} Pmd={:e} (MDB) {}",
            self.n,
            self.m,
            self.dof,
            self.pfa,
            self.threshold_chi2,
            clap::ValueEnum::to_possible_value(&self.design)
                .map_or_else(String::new, |v| v.get_name().to_string()),
            self.kappa,
            self.pmd,
            match &self.monte_carlo {
                Some(m) => format!("MC {} draws seed {}", m.draws, m.seed),
                None => "no MC".into(),
            }
        );
        let _ = writeln!(
            o,
            "biases and MDB in sigma units; P_CI unconditional, P(CI|D) given the test alarms"
        );
        let _ = writeln!(
            o,
            "{:<5} {:>6} {:>6} {:>6} {:>7} {:>8} {:>7} {:>7}",
            "sat", "az", "el", "h_ii", "bias", "lambda", "P_D", "MDB"
        );
        for s in &self.sats {
            let _ = writeln!(
                o,
                "{:<5} {:>6.1} {:>6.1} {:>6.3} {:>7.2} {:>8.2} {:>7.4} {:>7.2}",
                s.sat, s.az_deg, s.el_deg, s.h_ii, s.bias, s.lambda, s.p_d, s.mdb
            );
        }
        for (r, avg) in self.average.iter().enumerate() {
            let _ = writeln!(o);
            let _ = writeln!(
                o,
                "rule {:<12} {:>10} {:>9} {:>10} {:>8} {:>10} {:>10} {:>8}",
                avg.rule,
                "P_CI exact",
                "+-err",
                "P_CI MC",
                "+-se",
                "P(CI|D) ex",
                "P(CI|D) MC",
                "+-se"
            );
            for s in &self.sats {
                let c = &s.rules[r];
                let f = |v: Option<f64>, w: usize, p: usize| match v {
                    Some(x) => format!("{x:>w$.p$}"),
                    None => format!("{:>w$}", "-"),
                };
                let e = |v: Option<f64>, w: usize| match v {
                    Some(x) => format!("{x:>w$.1e}"),
                    None => format!("{:>w$}", "-"),
                };
                let _ = writeln!(
                    o,
                    "     {:<12} {} {} {} {} {} {} {}",
                    s.sat,
                    f(c.p_ci_exact, 10, 5),
                    e(c.p_ci_exact_err, 9),
                    f(c.p_ci_mc, 10, 5),
                    f(c.p_ci_mc_se, 8, 5),
                    f(c.p_ci_given_d_exact, 10, 5),
                    f(c.p_ci_given_d_mc, 10, 5),
                    f(c.p_ci_given_d_mc_se, 8, 5),
                );
            }
        }
        let _ = writeln!(o);
        let _ = writeln!(
            o,
            "average over satellites (mean P_D {:.4}):",
            self.mean_p_d
        );
        for a in &self.average {
            let f = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.5}"));
            let _ = writeln!(
                o,
                "  {:<12} P_CI {}  P(CI|D) {}",
                a.rule,
                f(a.p_ci),
                f(a.p_ci_given_d)
            );
        }
        o
    }
}
