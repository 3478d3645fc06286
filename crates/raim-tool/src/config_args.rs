//! Command-line configuration shared by the subcommands.

use clap::{Args, ValueEnum};
use raim_core::{Config, FiRule, Phase};

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum RuleArg {
    Mle,
    LraimFlat,
    Lraim,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum PhaseArg {
    EnRoute,
    Terminal,
    Npa,
}

#[derive(Debug, Clone, Args)]
pub struct ConfigArgs {
    /// Probability of false alarm per sample.
    #[arg(long, default_value = "3.3333e-7")]
    pub pfa: f64,
    /// Probability of missed detection (protection levels).
    #[arg(long, default_value = "1e-3")]
    pub pmd: f64,
    /// Fault identification rule.
    #[arg(long, value_enum, default_value_t = RuleArg::Lraim)]
    pub rule: RuleArg,
    /// kappa = tau^2/sigma^2 of the L-RAIM Gaussian bias prior.
    #[arg(long, default_value_t = raim_core::config::DEFAULT_KAPPA)]
    pub kappa: f64,
    /// Flight phase preset for the alert limits.
    #[arg(long, value_enum, default_value_t = PhaseArg::Npa)]
    pub phase: PhaseArg,
    /// Override the horizontal alert limit, m.
    #[arg(long)]
    pub hal_m: Option<f64>,
    /// Vertical alert limit, m (not monitored unless given).
    #[arg(long)]
    pub val_m: Option<f64>,
    /// Most exclusions per epoch.
    #[arg(long, default_value_t = 2)]
    pub max_exclusions: u8,
    /// Allow an exclusion even when excluding the runner-up also passes.
    #[arg(long)]
    pub allow_ambiguous: bool,
    /// Run the MCUSUM beside the snapshot test (docs/MCRAIM.md); --pfa is then the
    /// total per-epoch budget, split by --mcusum-share.
    #[arg(long)]
    pub mcusum: bool,
    /// MCUSUM reference value k, sigma units (a table value: 0.5, 1, 1.5).
    #[arg(long, default_value_t = raim_core::config::DEFAULT_MCUSUM_K)]
    pub mcusum_k: f64,
    /// Share of the false-alarm budget given to the snapshot test with --mcusum.
    #[arg(long, default_value_t = raim_core::config::DEFAULT_SNAPSHOT_SHARE)]
    pub mcusum_share: f64,
    /// Restart the MCUSUM at 0 on every change of the satellite set instead
    /// of transporting it (for comparison).
    #[arg(long)]
    pub mcusum_reset: bool,
    /// How long an MCUSUM exclusion is held, s.
    #[arg(long, default_value_t = raim_core::config::DEFAULT_MCUSUM_HOLD_S)]
    pub mcusum_hold_s: f64,
    /// Correlation time of the Gauss-Markov error model the MCUSUM whitens
    /// against, s (0 = white noise, up to 3600; docs/MCRAIM.md "Time-correlated
    /// errors").
    #[arg(long, default_value_t = 0.0)]
    pub mcusum_tau_s: f64,
    /// FDE by error reconstruction over constraint groups
    /// (docs/MULTIFAULT.md) for up to this many simultaneous faults (1-3);
    /// also raises --max-exclusions to it. Default: today's FDE.
    #[arg(long)]
    pub multifault_t_max: Option<u8>,
    /// Constraint groups searched per epoch by the reconstruction FDE.
    #[arg(long, default_value_t = 1000)]
    pub group_budget: u16,
}

impl ConfigArgs {
    pub fn config(&self) -> Config {
        let phase = match self.phase {
            PhaseArg::EnRoute => Phase::EnRoute,
            PhaseArg::Terminal => Phase::Terminal,
            PhaseArg::Npa => Phase::Npa,
        };
        let mut c = Config::preset(phase);
        c.pfa = self.pfa;
        c.pmd = self.pmd;
        c.rule = match self.rule {
            RuleArg::Mle => FiRule::Mle,
            RuleArg::LraimFlat => FiRule::LraimFlat,
            RuleArg::Lraim => FiRule::LraimGaussian { kappa: self.kappa },
        };
        if let Some(h) = self.hal_m {
            c.alert.hal_m = h;
        }
        c.alert.val_m = self.val_m;
        c.max_exclusions = self.max_exclusions;
        c.require_unique_exclusion = !self.allow_ambiguous;
        if let Some(t_max) = self.multifault_t_max {
            c.fde_method = raim_core::FdeMethod::Reconstruction {
                t_max,
                group_budget: self.group_budget,
            };
            c.max_exclusions = c.max_exclusions.max(t_max);
        }
        if self.mcusum {
            c = c.split_false_alarm_budget(self.mcusum_share);
            c.mcusum.k = self.mcusum_k;
            c.mcusum.hold_s = self.mcusum_hold_s;
            c.mcusum.correlation_time_s = self.mcusum_tau_s;
            if self.mcusum_reset {
                c.mcusum.carry = raim_core::config::Carry::Reset;
            }
        }
        c
    }
}

impl ConfigArgs {
    /// An option given on the command line (`given`) that the rest of the
    /// configuration would ignore, as a usage message naming both.
    pub fn ignored(&self, given: &dyn Fn(&str) -> bool) -> Option<String> {
        for id in [
            "mcusum_k",
            "mcusum_share",
            "mcusum_reset",
            "mcusum_hold_s",
            "mcusum_tau_s",
        ] {
            if given(id) && !self.mcusum {
                return Some(format!(
                    "'--{}' would be ignored: it needs --mcusum",
                    id.replace('_', "-")
                ));
            }
        }
        if given("group_budget") && self.multifault_t_max.is_none() {
            return Some("'--group-budget' would be ignored: it needs --multifault-t-max".into());
        }
        if given("kappa") && !matches!(self.rule, RuleArg::Lraim) {
            return Some(
                "'--kappa' would be ignored: it is the prior of --rule lraim, not of the rule given"
                    .into(),
            );
        }
        None
    }
}
