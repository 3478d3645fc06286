//! Snapshot detection (SPEC §3): D^2 = p^T p against T^2, the chi-square
//! quantile at 1 - Pfa with n - m degrees of freedom. Thresholds and the
//! protection-level non-centrality are cached per dof, since Pfa and Pmd
//! rarely change while the dof changes every few epochs.

use crate::error::RaimError;
use crate::snapshot::threshold_table;
use crate::stats::dist;

/// One chi-square test: statistic, threshold and degrees of freedom.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TestStatistic {
    /// D^2 = p^T p (weighted SSE), dimensionless.
    pub statistic: f64,
    /// T^2 = chi2 quantile(1 - Pfa; dof).
    pub threshold: f64,
    /// Degrees of freedom n - m.
    pub dof: u32,
}

impl TestStatistic {
    /// The zero statistic (the derived `Default`), for `const fn`
    /// constructors.
    pub const ZERO: Self = TestStatistic {
        statistic: 0.0,
        threshold: 0.0,
        dof: 0,
    };
    /// Alarm if D^2 >= T^2.
    pub fn alarm(&self) -> bool {
        !(self.statistic < self.threshold)
    }
}

/// Per-dof cache of T^2 and lambda_md for one (Pfa, Pmd) pair, and of the
/// uniqueness check's chi-square quantile at 1 - pwe (docs/CORE.md, FDE 3).
///
/// A cold entry (a fresh engine, or a dof not seen yet) is first looked up
/// in the precomputed tables of `threshold_table.rs` (the presets' Pfa,
/// Pfa / 2 for the MCUSUM split, Pmd 1e-3, pwe 1e-3; dof 1..=31), which
/// hold exactly the values `dist` computes (test
/// `tables_equal_the_exact_quantiles`); only a configuration off the table
/// pays for the quantile inversions.
#[derive(Debug, Clone)]
pub struct Thresholds<const N: usize> {
    pfa: f64,
    pmd: f64,
    pwe: f64,
    t2: [f64; N],
    lambda: [f64; N],
    t2_we: [f64; N],
}

impl<const N: usize> Default for Thresholds<N> {
    fn default() -> Self {
        Self::empty()
    }
}

impl<const N: usize> Thresholds<N> {
    /// No threshold computed yet (NaN: never a valid threshold).
    pub const fn empty() -> Self {
        Thresholds {
            pfa: f64::NAN,
            pmd: f64::NAN,
            pwe: f64::NAN,
            t2: [f64::NAN; N],
            lambda: [f64::NAN; N],
            t2_we: [f64::NAN; N],
        }
    }
}

fn dof_checked<const N: usize>(dof: usize) -> Result<u32, RaimError> {
    let dof_u32 = u32::try_from(dof).unwrap_or(u32::MAX);
    if dof == 0 || dof >= N {
        return Err(RaimError::InvalidDof {
            dof: dof_u32,
            max: N.saturating_sub(1) as u32,
        });
    }
    Ok(dof_u32)
}

impl<const N: usize> Thresholds<N> {
    /// T^2 and lambda_md for `dof` (1..N), computing them on first use.
    pub fn get(&mut self, pfa: f64, pmd: f64, dof: usize) -> Result<(f64, f64), RaimError> {
        if pfa != self.pfa || pmd != self.pmd {
            self.pfa = pfa;
            self.pmd = pmd;
            self.t2 = [f64::NAN; N];
            self.lambda = [f64::NAN; N];
        }
        let dof_u32 = dof_checked::<N>(dof)?;
        let (Some(t2), Some(lambda)) = (self.t2.get_mut(dof), self.lambda.get_mut(dof)) else {
            return Err(RaimError::InvalidDof {
                dof: dof_u32,
                max: N.saturating_sub(1) as u32,
            });
        };
        if t2.is_nan() {
            *t2 = match threshold_table::t2(pfa, dof) {
                Some(v) => v,
                None => dist::chi2_quantile_upper(pfa, dof_u32)?,
            };
            *lambda = match threshold_table::lambda(pfa, pmd, dof) {
                Some(v) => v,
                None => dist::ncx2_lambda(pfa, pmd, dof_u32)?,
            };
        }
        Ok((*t2, *lambda))
    }

    /// The chi-square quantile at 1 - `pwe` for `dof` (1..N), the
    /// uniqueness check's threshold, computing it on first use.
    pub fn wrong_exclusion(&mut self, pwe: f64, dof: usize) -> Result<f64, RaimError> {
        if pwe != self.pwe {
            self.pwe = pwe;
            self.t2_we = [f64::NAN; N];
        }
        let dof_u32 = dof_checked::<N>(dof)?;
        let Some(t2) = self.t2_we.get_mut(dof) else {
            return Err(RaimError::InvalidDof {
                dof: dof_u32,
                max: N.saturating_sub(1) as u32,
            });
        };
        if t2.is_nan() {
            *t2 = match threshold_table::t2(pwe, dof) {
                Some(v) => v,
                None => dist::chi2_quantile_upper(pwe, dof_u32)?,
            };
        }
        Ok(*t2)
    }
}
