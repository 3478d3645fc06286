//! The decision threshold lambda of seed 004 eq. 13 from an allocated
//! per-epoch false-alarm probability (SPEC §10): looked up in a table made
//! by a seeded Monte Carlo of the monitor on nominal data simulated from
//! the filter's own measurement and process models (never on the data the
//! monitor is judged on), as the MCUSUM's h table is
//! (`sequential::mcusum_table`).
//!
//! The null distribution of D_k depends on the filter and its particle
//! count (the Monte Carlo noise of the predictive densities), the window
//! U, the likelihood law and the model: the ranging sigma, the process
//! noise, the prior spreads and the GA mutation step, with the epoch
//! interval and the sky of the simulation. The table therefore has one row
//! per (model profile, filter, particle count, likelihood), one column per
//! window in [`WINDOWS`] and, in each, one threshold per false-alarm node
//! in [`LOG10_PFA`].
//!
//! Each threshold is the order statistic of the block maxima of D_k
//! (blocks of U epochs) that bounds the block exceedance probability by
//! the node's Pfa with 95 % confidence (binomial); since an epoch's alarm
//! implies its block's, the per-epoch false-alarm rate is then at most
//! Pfa. A node the run was too short to certify is NaN, and asking for it
//! is `PfError::NotCalibrated`. Between nodes the threshold is linear in
//! log10 Pfa; a Pfa above the largest node takes that node's threshold
//! (conservative). docs/PF.md "Thresholds" has the command that makes the
//! table and the check on real data.

use super::config::{Likelihood, PfConfig, ProcessModel};
use super::error::PfError;
use super::threshold_table::{LOG10_PFA, PROFILES, ROWS, WINDOWS};

/// Number of false-alarm nodes per window.
pub const N_PFA: usize = LOG10_PFA.len();
/// Number of windows per row.
pub const N_WINDOWS: usize = WINDOWS.len();

/// A model the table was calibrated for: the `PfConfig` fields that shape
/// the null distribution of D_k (matched exactly), and the simulated data
/// they were calibrated on (the epoch interval and the sky, documented;
/// the monitor cannot check them).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Profile {
    /// The profile's name in the table and the docs.
    pub name: &'static str,
    /// `PfConfig::sigma_m`, m.
    pub sigma_m: f64,
    /// `PfConfig::process`.
    pub process: ProcessModel,
    /// `PfConfig::init_position_m`, m.
    pub init_position_m: f64,
    /// `PfConfig::init_clock_m`, m.
    pub init_clock_m: f64,
    /// `PfConfig::init_drift_m_s`, m/s.
    pub init_drift_m_s: f64,
    /// `PfConfig::mutation_m`, m.
    pub mutation_m: f64,
    /// Epoch interval of the simulated data, s.
    pub epoch_s: f64,
    /// Satellites of the simulated sky: GPS, then Galileo.
    /// GPS satellites of the simulated sky.
    pub gps_sats: usize,
    /// Galileo satellites of the simulated sky.
    pub galileo_sats: usize,
}

impl Profile {
    /// `cfg` has this profile's model (bitwise-equal fields).
    pub fn matches(&self, cfg: &PfConfig) -> bool {
        self.sigma_m == cfg.sigma_m
            && self.process == cfg.process
            && self.init_position_m == cfg.init_position_m
            && self.init_clock_m == cfg.init_clock_m
            && self.init_drift_m_s == cfg.init_drift_m_s
            && self.mutation_m == cfg.mutation_m
    }

    /// A `PfConfig` with this profile's model, `likelihood`, `window` and
    /// `pfa`; the other fields at their defaults.
    pub fn config(&self, likelihood: Likelihood, window: usize, pfa: f64) -> PfConfig {
        PfConfig {
            process: self.process,
            likelihood,
            sigma_m: self.sigma_m,
            init_position_m: self.init_position_m,
            init_clock_m: self.init_clock_m,
            init_drift_m_s: self.init_drift_m_s,
            mutation_m: self.mutation_m,
            window,
            pfa,
            ..PfConfig::default()
        }
    }
}

/// One calibrated row: `threshold[w][j]` for window `WINDOWS[w]` at Pfa
/// 10^`LOG10_PFA[j]` (NaN: not certified by the run).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Row {
    /// Index into `PROFILES`.
    pub profile: usize,
    /// `Estimator::KIND`: "ekf", "pf" or "gapf".
    pub kind: &'static str,
    /// `Estimator::PARTICLES` (0 for the EKF).
    pub particles: usize,
    /// The likelihood law the row was calibrated with.
    pub likelihood: Likelihood,
    /// The decision thresholds, nats of accumulated LLR.
    pub threshold: [[f64; N_PFA]; N_WINDOWS],
}

/// The calibrated row for this filter and configuration.
pub fn row(kind: &str, particles: usize, cfg: &PfConfig) -> Result<&'static Row, PfError> {
    let profile = PROFILES
        .iter()
        .position(|p| p.matches(cfg))
        .ok_or(PfError::NotCalibrated {
            field: "sigma_m (model profile)",
            value: cfg.sigma_m,
        })?;
    let same_filter = |r: &&Row| r.profile == profile && r.kind == kind && r.particles == particles;
    match ROWS
        .iter()
        .filter(same_filter)
        .find(|r| r.likelihood == cfg.likelihood)
    {
        Some(r) => Ok(r),
        None if ROWS.iter().any(|r| same_filter(&r)) => Err(PfError::NotCalibrated {
            field: "likelihood",
            value: cfg.likelihood.variance_factor(),
        }),
        None => Err(PfError::NotCalibrated {
            field: "particles",
            value: particles as f64,
        }),
    }
}

/// The decision threshold for `cfg.window` at `cfg.pfa`: the table value,
/// linear in log10 Pfa between nodes.
pub fn lookup(kind: &str, particles: usize, cfg: &PfConfig) -> Result<f64, PfError> {
    let r = row(kind, particles, cfg)?;
    let w = WINDOWS
        .iter()
        .position(|&w| w == cfg.window)
        .ok_or(PfError::NotCalibrated {
            field: "window",
            value: cfg.window as f64,
        })?;
    let t = r.threshold.get(w).ok_or(PfError::NotCalibrated {
        field: "window",
        value: cfg.window as f64,
    })?;
    interpolate(t, cfg.pfa)
}

/// Linear interpolation in log10 Pfa over the descending nodes.
fn interpolate(t: &[f64; N_PFA], pfa: f64) -> Result<f64, PfError> {
    let bad = PfError::NotCalibrated {
        field: "pfa",
        value: pfa,
    };
    if !(pfa > 0.0 && pfa < 1.0) {
        return Err(bad);
    }
    let x = libm::log10(pfa);
    let [first, ..] = LOG10_PFA;
    if x >= first {
        return t.first().copied().filter(|v| v.is_finite()).ok_or(bad);
    }
    for (i, pair) in LOG10_PFA.windows(2).enumerate() {
        let (Some(&hi), Some(&lo)) = (pair.first(), pair.get(1)) else {
            continue;
        };
        if x <= hi && x >= lo {
            let (Some(&a), Some(&b)) = (t.get(i), t.get(i + 1)) else {
                return Err(bad);
            };
            if !(a.is_finite() && b.is_finite()) {
                return Err(bad);
            }
            let f = (hi - x) / (hi - lo);
            return Ok(a + f * (b - a));
        }
    }
    Err(bad)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every profile's own configuration finds a row for each filter the
    /// table holds, the nodes come back exactly, and between nodes the
    /// threshold lies between its neighbours.
    #[test]
    fn lookup_returns_nodes_and_interpolates() {
        for r in ROWS.iter() {
            let p = PROFILES[r.profile];
            for (w, &window) in WINDOWS.iter().enumerate() {
                for (j, &l) in LOG10_PFA.iter().enumerate() {
                    let cfg = p.config(r.likelihood, window, 10f64.powf(l));
                    let got = lookup(r.kind, r.particles, &cfg);
                    let want = r.threshold[w][j];
                    if want.is_finite() {
                        let got = got.unwrap();
                        assert!((got - want).abs() <= 1e-9 * want.abs().max(1.0));
                    } else {
                        assert!(matches!(
                            got,
                            Err(PfError::NotCalibrated { field: "pfa", .. })
                        ));
                    }
                }
                let (a, b) = (r.threshold[w][0], r.threshold[w][1]);
                if a.is_finite() && b.is_finite() {
                    let mid = 10f64.powf(0.5 * (LOG10_PFA[0] + LOG10_PFA[1]));
                    let cfg = p.config(r.likelihood, window, mid);
                    let got = lookup(r.kind, r.particles, &cfg).unwrap();
                    assert!(got >= a.min(b) - 1e-12 && got <= a.max(b) + 1e-12);
                }
            }
        }
    }

    /// The interpolation on a hand-made row (thresholds 10, 20, NaN at
    /// log10 Pfa -2, -2.5, -3): Pfa at or above 1e-2 takes the first node;
    /// between -2 and -2.5 it is linear in log10 Pfa (10^-2.25 gives 15);
    /// a segment that touches a NaN (uncertified) node, a Pfa past the last
    /// node, and a Pfa that is NaN, 0 or 1 are `NotCalibrated` naming Pfa
    /// with the value. A NaN first node refuses Pfa above 1e-2 too.
    #[test]
    fn interpolation_refuses_uncertified_segments() {
        let row = [10.0, 20.0, f64::NAN];
        assert_eq!(interpolate(&row, 0.5), Ok(10.0));
        let mid = interpolate(&row, 10f64.powf(-2.25)).unwrap();
        assert!((mid - 15.0).abs() < 1e-12, "{mid}");
        for pfa in [10f64.powf(-2.75), 1e-4, 0.0, 1.0, f64::NAN] {
            match interpolate(&row, pfa) {
                Err(PfError::NotCalibrated {
                    field: "pfa",
                    value,
                }) => {
                    assert!(value.to_bits() == pfa.to_bits(), "{pfa}")
                }
                other => panic!("{pfa}: {other:?}"),
            }
        }
        assert!(interpolate(&[f64::NAN, 1.0, 2.0], 0.5).is_err());
    }

    /// A profile matches a configuration only with every model field
    /// equal: changing any one of the initial spreads or the mutation
    /// breaks the match.
    #[test]
    fn profile_match_needs_every_model_field() {
        let r = ROWS[0];
        let p = PROFILES[r.profile];
        let ok = p.config(r.likelihood, WINDOWS[0], 1e-2);
        assert!(p.matches(&ok));
        let changed = [
            PfConfig {
                init_position_m: ok.init_position_m + 1.0,
                ..ok
            },
            PfConfig {
                init_clock_m: ok.init_clock_m + 1.0,
                ..ok
            },
            PfConfig {
                init_drift_m_s: ok.init_drift_m_s + 1.0,
                ..ok
            },
            PfConfig {
                mutation_m: ok.mutation_m + 1.0,
                ..ok
            },
        ];
        for (i, c) in changed.iter().enumerate() {
            assert!(!p.matches(c), "{i}");
        }
    }

    /// A model, window, filter or Pfa the table does not cover is a typed
    /// error naming it.
    ///
    /// Verifies: SAFE-T5
    #[test]
    fn uncovered_configurations_are_refused() {
        let r = ROWS[0];
        let p = PROFILES[r.profile];
        let ok = p.config(r.likelihood, WINDOWS[0], 1e-2);
        assert!(lookup(r.kind, r.particles, &ok).is_ok());
        let other_sigma = PfConfig {
            sigma_m: p.sigma_m * 1.5,
            ..ok
        };
        assert!(matches!(
            lookup(r.kind, r.particles, &other_sigma),
            Err(PfError::NotCalibrated {
                field: "sigma_m (model profile)",
                ..
            })
        ));
        let other_window = PfConfig { window: 63, ..ok };
        assert!(matches!(
            lookup(r.kind, r.particles, &other_window),
            Err(PfError::NotCalibrated {
                field: "window",
                ..
            })
        ));
        assert!(matches!(
            lookup(r.kind, 77, &ok),
            Err(PfError::NotCalibrated {
                field: "particles",
                ..
            })
        ));
        let tiny = PfConfig { pfa: 1e-9, ..ok };
        assert!(matches!(
            lookup(r.kind, r.particles, &tiny),
            Err(PfError::NotCalibrated { field: "pfa", .. })
        ));
        let odd_lik = PfConfig {
            likelihood: Likelihood::StudentT { nu: 7.5 },
            ..ok
        };
        assert!(matches!(
            lookup(r.kind, r.particles, &odd_lik),
            Err(PfError::NotCalibrated {
                field: "likelihood",
                ..
            })
        ));
    }
}

#[cfg(test)]
#[path = "threshold_cov_tests.rs"]
mod cov_tests;
