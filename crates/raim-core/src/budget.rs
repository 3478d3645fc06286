//! One false-alarm and integrity budget across the monitors
//! (docs/BUDGET.md).
//!
//! **False alarms.** The user configures one total false-alarm probability
//! per epoch, P_FA. Each monitor that can raise an alarm or an exclusion on
//! fault-free data gets a share, and the shares sum to 1, so by the union
//! bound the combined per-epoch false-alarm probability is at most
//! P_FA (SPEC §7.4 for the snapshot/MCUSUM pair: 1 / ARL0_combined ~
//! Pfa_snapshot + 1 / ARL0_mcusum):
//!
//! - snapshot test: `Config::pfa` = share x P_FA;
//! - MCUSUM: `McusumConfig::arl0` = 1 / (share x P_FA) epochs (off at 0);
//! - ARAIM: P_FA,vert + P_FA,hor = share x P_FA, split in the ADD's ratio
//!   3.9e-6 : 9e-8;
//! - the particle filters: `PfConfig::pfa` = share x P_FA (0 by default:
//!   not run), their LLR threshold from the calibrated table (docs/PF.md);
//! - PCA: share 0. Its threshold is not verified against an allocation on
//!   real data, so it does not drive the alarm output (docs/ESQ.md).
//!
//! The multiple-fault search (`FdeMethod::Reconstruction`) runs only after
//! the snapshot test has detected: it adds no false alarm of its own, and
//! its cost on fault-free data is how the snapshot test's false detections
//! end (alarm or exclusion), which the Monte Carlo reports.
//!
//! **Integrity under a fault.** The user configures the conditional
//! probability per epoch that a fault leads to hazardously misleading
//! information, P_MD,total. A fault is hazardous if it is missed (the
//! protection level holds P_md) or if the wrong satellites are excluded and
//! the fault stays in the solution (the uniqueness check holds pwe: an
//! exclusion stands only if every other explanation of the same or larger
//! size is rejected at 1 - pwe, so the true fault set, whose subset
//! statistic is chi-square, survives as an alternative with probability
//! 1 - pwe, and a wrong exclusion needs it rejected: at most pwe). So
//! P_MD,total = P_md + pwe, split by `wrong_exclusion_share`.

use crate::araim::AraimConfig;
use crate::config::Config;
use crate::error::RaimError;

/// The default total false-alarm probability per epoch (1e-5 / h over ~30
/// independent samples, SPEC §3).
pub const DEFAULT_P_FA_TOTAL: f64 = 3.3333e-7;
/// The default conditional integrity budget per epoch under a fault:
/// P_md + pwe.
pub const DEFAULT_P_MD_TOTAL: f64 = 2e-3;
/// The default share of `DEFAULT_P_MD_TOTAL` held by the wrong-exclusion
/// check: half, so P_md = pwe = 1e-3.
pub const DEFAULT_WRONG_EXCLUSION_SHARE: f64 = 0.5;
/// The ADD's vertical share of ARAIM's continuity budget,
/// 3.9e-6 / (3.9e-6 + 9e-8).
pub const ARAIM_VERTICAL_SHARE: f64 = 3.9e-6 / (3.9e-6 + 9e-8);
/// How far the false-alarm shares may sum from 1 (rounding of decimal
/// inputs).
pub const SHARE_SUM_TOL: f64 = 1e-9;

/// Shares of the per-epoch false-alarm budget, one per monitor; they sum
/// to 1.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FalseAlarmShares {
    /// The snapshot chi-square test.
    pub snapshot: f64,
    /// The MCUSUM (0: off).
    pub mcusum: f64,
    /// ARAIM's solution-separation tests.
    pub araim: f64,
    /// The PCA constellation monitor (0: not on the integrity path).
    pub pca: f64,
    /// The particle filters' LLR test (0: not run).
    pub pf: f64,
}

impl FalseAlarmShares {
    /// The snapshot monitor alone.
    pub const SNAPSHOT_ONLY: Self = Self {
        snapshot: 1.0,
        mcusum: 0.0,
        araim: 0.0,
        pca: 0.0,
        pf: 0.0,
    };

    /// The shares in a fixed order with their names.
    pub fn named(&self) -> [(&'static str, f64); 5] {
        [
            ("share_snapshot", self.snapshot),
            ("share_mcusum", self.mcusum),
            ("share_araim", self.araim),
            ("share_pca", self.pca),
            ("share_pf", self.pf),
        ]
    }
}

/// The user's budget and its allocation among the monitors.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Budget {
    /// Total false-alarm probability per epoch, (0, 1).
    pub p_fa_total: f64,
    /// Its split among the monitors.
    pub shares: FalseAlarmShares,
    /// Conditional integrity budget per epoch under a fault,
    /// P_md + pwe, (0, 1).
    pub p_md_total: f64,
    /// Share of `p_md_total` held by the wrong-exclusion check (pwe), (0, 1).
    pub wrong_exclusion_share: f64,
}

impl Default for Budget {
    fn default() -> Self {
        Self {
            p_fa_total: DEFAULT_P_FA_TOTAL,
            shares: FalseAlarmShares::SNAPSHOT_ONLY,
            p_md_total: DEFAULT_P_MD_TOTAL,
            wrong_exclusion_share: DEFAULT_WRONG_EXCLUSION_SHARE,
        }
    }
}

fn out_of_range(field: &'static str, value: f64, min: f64, max: f64) -> RaimError {
    RaimError::OutOfRange {
        field,
        value,
        min,
        max,
    }
}

impl Budget {
    /// Every probability in (0, 1), every share in [0, 1], the shares
    /// summing to 1 within `SHARE_SUM_TOL`.
    ///
    /// # Errors
    /// `OutOfRange` naming the first offending field.
    pub fn validate(&self) -> Result<(), RaimError> {
        for (field, v) in [
            ("p_fa_total", self.p_fa_total),
            ("p_md_total", self.p_md_total),
            ("wrong_exclusion_share", self.wrong_exclusion_share),
        ] {
            if !(v > 0.0 && v < 1.0) {
                return Err(out_of_range(field, v, 0.0, 1.0));
            }
        }
        let mut sum = 0.0;
        for (field, v) in self.shares.named() {
            if !(0.0..=1.0).contains(&v) {
                return Err(out_of_range(field, v, 0.0, 1.0));
            }
            sum += v;
        }
        if !(libm::fabs(sum - 1.0) <= SHARE_SUM_TOL) {
            return Err(out_of_range(
                "share_sum",
                sum,
                1.0 - SHARE_SUM_TOL,
                1.0 + SHARE_SUM_TOL,
            ));
        }
        Ok(())
    }

    /// P_md of the protection levels: (1 - share) x P_MD,total.
    pub fn pmd(&self) -> f64 {
        self.p_md_total * (1.0 - self.wrong_exclusion_share)
    }

    /// pwe of the uniqueness checks: share x P_MD,total.
    pub fn pwe(&self) -> f64 {
        self.p_md_total * self.wrong_exclusion_share
    }

    /// A monitor's false-alarm probability per epoch: share x P_FA.
    pub fn pfa_of(&self, share: f64) -> f64 {
        self.p_fa_total * share
    }

    /// The snapshot engine's configuration: `pfa`, the MCUSUM's `enabled`
    /// and `arl0`, `pmd` and `pwe` from the allocation; every other field
    /// kept.
    ///
    /// # Errors
    /// The budget's `validate`, then the configuration's.
    pub fn apply(&self, mut cfg: Config) -> Result<Config, RaimError> {
        self.validate()?;
        cfg.pfa = self.pfa_of(self.shares.snapshot);
        cfg.mcusum.enabled = self.shares.mcusum > 0.0;
        if cfg.mcusum.enabled {
            cfg.mcusum.arl0 = 1.0 / self.pfa_of(self.shares.mcusum);
        }
        cfg.pmd = self.pmd();
        cfg.pwe = self.pwe();
        cfg.validate()?;
        Ok(cfg)
    }

    /// ARAIM's continuity budgets: P_FA,vert + P_FA,hor = share x P_FA in
    /// the ADD's ratio.
    ///
    /// # Errors
    /// The budget's `validate`; `OutOfRange { field: "share_araim" }` when
    /// ARAIM has no share.
    pub fn apply_araim(&self, mut cfg: AraimConfig) -> Result<AraimConfig, RaimError> {
        self.validate()?;
        let p = self.pfa_of(self.shares.araim);
        if !(p > 0.0) {
            return Err(out_of_range("share_araim", self.shares.araim, 0.0, 1.0));
        }
        cfg.pfa_vert = p * ARAIM_VERTICAL_SHARE;
        cfg.pfa_hor = p * (1.0 - ARAIM_VERTICAL_SHARE);
        Ok(cfg)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Phase;

    /// The presets are the default budget: the same bits as before the
    /// allocation existed (the firmware's answers do not move).
    #[test]
    fn default_budget_is_the_preset() {
        let b = Budget::default();
        assert_eq!(b.pmd(), 1e-3);
        assert_eq!(b.pwe(), 1e-3);
        let cfg = b.apply(Config::preset(Phase::Npa)).unwrap();
        assert_eq!(cfg, Config::preset(Phase::Npa));
    }

    /// Verifies: SPEC-12
    #[test]
    fn shares_sum_to_the_total() {
        const REL_TOL: f64 = 1e-12;
        let b = Budget {
            p_fa_total: 1e-4,
            shares: FalseAlarmShares {
                snapshot: 0.5,
                mcusum: 0.25,
                araim: 0.25,
                pca: 0.0,
                pf: 0.0,
            },
            p_md_total: 2e-3,
            wrong_exclusion_share: 0.25,
        };
        let cfg = b.apply(Config::default()).unwrap();
        let a = b.apply_araim(AraimConfig::default()).unwrap();
        let sum = cfg.pfa + 1.0 / cfg.mcusum.arl0 + a.pfa_vert + a.pfa_hor;
        assert!((sum - 1e-4).abs() < REL_TOL * 1e-4, "{sum}");
        assert!((cfg.pmd + cfg.pwe - 2e-3).abs() < REL_TOL * 2e-3);
        assert!((cfg.pwe - 5e-4).abs() < REL_TOL * 5e-4);
        assert!((a.pfa_vert / a.pfa_hor - 3.9e-6 / 9e-8).abs() < 1e-9 * 43.3);
    }

    #[test]
    fn bad_budgets_are_typed() {
        let bad = |b: Budget, field: &str| {
            assert!(
                matches!(b.validate(), Err(RaimError::OutOfRange { field: f, .. }) if f == field),
                "{field}"
            );
        };
        let d = Budget::default();
        bad(
            Budget {
                p_fa_total: 0.0,
                ..d
            },
            "p_fa_total",
        );
        bad(
            Budget {
                p_md_total: f64::NAN,
                ..d
            },
            "p_md_total",
        );
        bad(
            Budget {
                wrong_exclusion_share: 1.0,
                ..d
            },
            "wrong_exclusion_share",
        );
        let mut s = d;
        s.shares.pca = -0.1;
        bad(s, "share_pca");
        let mut s = d;
        s.shares.araim = 0.5;
        bad(s, "share_sum");
        assert!(matches!(
            d.apply_araim(AraimConfig::default()),
            Err(RaimError::OutOfRange {
                field: "share_araim",
                ..
            })
        ));
    }
}
