//! Snapshot detection (SPEC §3): D^2 = p^T p against T^2, the chi-square
//! quantile at 1 - Pfa with n - m degrees of freedom. Thresholds and the
//! protection-level non-centrality are cached per dof, since Pfa and Pmd
//! rarely change while the dof changes every few epochs.

use crate::error::RaimError;
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
    pub dof: u32,
}

impl TestStatistic {
    /// Alarm if D^2 >= T^2.
    pub fn alarm(&self) -> bool {
        !(self.statistic < self.threshold)
    }
}

/// Per-dof cache of T^2 and lambda_md for one (Pfa, Pmd) pair.
#[derive(Debug, Clone)]
pub struct Thresholds<const N: usize> {
    pfa: f64,
    pmd: f64,
    t2: [f64; N],
    lambda: [f64; N],
}

impl<const N: usize> Default for Thresholds<N> {
    fn default() -> Self {
        Thresholds {
            pfa: f64::NAN,
            pmd: f64::NAN,
            t2: [f64::NAN; N],
            lambda: [f64::NAN; N],
        }
    }
}

impl<const N: usize> Thresholds<N> {
    /// T^2 and lambda_md for `dof` (1..N), computing them on first use.
    pub fn get(&mut self, pfa: f64, pmd: f64, dof: usize) -> Result<(f64, f64), RaimError> {
        if pfa != self.pfa || pmd != self.pmd {
            *self = Thresholds {
                pfa,
                pmd,
                ..Thresholds::default()
            };
        }
        let dof_u32 = u32::try_from(dof).unwrap_or(u32::MAX);
        let invalid = RaimError::InvalidDof {
            dof: dof_u32,
            max: N.saturating_sub(1) as u32,
        };
        let (Some(t2), Some(lambda)) = (self.t2.get_mut(dof), self.lambda.get_mut(dof)) else {
            return Err(invalid);
        };
        if dof == 0 {
            return Err(invalid);
        }
        if t2.is_nan() {
            *t2 = dist::chi2_quantile_upper(pfa, dof_u32)?;
            *lambda = dist::ncx2_lambda(pfa, pmd, dof_u32)?;
        }
        Ok((*t2, *lambda))
    }
}
