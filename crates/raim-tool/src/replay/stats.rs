//! Confidence statements for the replay studies: the Clopper-Pearson
//! interval of a proportion, distribution-free intervals of a quantile from
//! order statistics, and the binomial bound a false-alarm count is held to.

use statrs::distribution::{Beta, Binomial, ContinuousCDF, DiscreteCDF};

/// Clopper-Pearson interval of a proportion `k / n` at confidence `conf`:
/// the Beta(k, n - k + 1) quantile at (1 - conf) / 2 and the
/// Beta(k + 1, n - k) quantile at (1 + conf) / 2 (0 and 1 at the ends).
pub fn clopper_pearson(k: usize, n: usize, conf: f64) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let a = (1.0 - conf) / 2.0;
    let (kf, nf) = (k as f64, n as f64);
    let lo = if k == 0 {
        0.0
    } else {
        Beta::new(kf, nf - kf + 1.0).map_or(f64::NAN, |b| b.inverse_cdf(a))
    };
    let hi = if k == n {
        1.0
    } else {
        Beta::new(kf + 1.0, nf - kf).map_or(f64::NAN, |b| b.inverse_cdf(1.0 - a))
    };
    (lo, hi)
}

/// The `q` quantile of `sorted` (ascending; the order statistic of rank
/// ceil(q n)) with a distribution-free interval at confidence `conf`: the
/// order statistics x_(l) and x_(u) with P(x_(l) <= xi_q <= x_(u)) >= conf,
/// from Binomial(n, q), each side at (1 - conf) / 2. None where the sample
/// is too small for that side (e.g. the upper side of a 95th percentile
/// needs n >= 72: 1 - 0.95^n >= 0.975).
pub fn quantile_ci(sorted: &[f64], q: f64, conf: f64) -> (Option<f64>, Option<f64>, Option<f64>) {
    let n = sorted.len();
    if n == 0 {
        return (None, None, None);
    }
    let rank = ((q * n as f64).ceil() as usize).clamp(1, n);
    let est = sorted.get(rank - 1).copied();
    let Ok(b) = Binomial::new(q, n as u64) else {
        return (est, None, None);
    };
    let a = (1.0 - conf) / 2.0;
    // xi_q >= x_(l) when at least l of the n fall below xi_q:
    // P(B >= l) = 1 - cdf(l - 1) >= 1 - a; the largest such l.
    let lo = (1..=n)
        .rev()
        .find(|&l| b.cdf(l as u64 - 1) <= a)
        .and_then(|l| sorted.get(l - 1).copied());
    // xi_q <= x_(u) when fewer than u fall below: P(B <= u - 1) >= 1 - a;
    // the smallest such u.
    let hi = (1..=n)
        .find(|&u| b.cdf(u as u64 - 1) >= 1.0 - a)
        .and_then(|u| sorted.get(u - 1).copied());
    (est, lo, hi)
}

/// The 99 % binomial bound of a false-alarm count: the least b with
/// P(X <= b) >= 0.99 for X ~ Binomial(n, p). A count above b rejects the
/// allocation p at the 1 % level.
pub fn binomial_bound_99(n: usize, p: f64) -> u64 {
    let Ok(b) = Binomial::new(p.clamp(0.0, 1.0), n as u64) else {
        return n as u64;
    };
    (0..=n as u64)
        .find(|&k| b.cdf(k) >= 0.99)
        .unwrap_or(n as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Interval endpoints compared with the printed values (conf 0.95).
    const TOL: f64 = 1e-4;

    #[test]
    fn clopper_pearson_matches_known_intervals() {
        // 0 of 10: [0, 1 - 0.025^(1/10)] = [0, 0.30850]; 5 of 10:
        // [0.18709, 0.81291] (the standard Clopper-Pearson table values).
        let (lo, hi) = clopper_pearson(0, 10, 0.95);
        assert!(lo == 0.0 && (hi - (1.0 - 0.025f64.powf(0.1))).abs() < TOL);
        let (lo, hi) = clopper_pearson(5, 10, 0.95);
        assert!(
            (lo - 0.18709).abs() < TOL && (hi - 0.81291).abs() < TOL,
            "{lo} {hi}"
        );
    }

    #[test]
    fn quantile_interval_brackets_the_estimate() {
        let v: Vec<f64> = (1..=100).map(f64::from).collect();
        let (e, l, h) = quantile_ci(&v, 0.5, 0.95);
        // Median of 1..100, rank 50; the 95 % order-statistic interval is
        // (x_40, x_61) (Binomial(100, 0.5): cdf(39) = 0.018, cdf(60) = 0.982).
        assert_eq!((e, l, h), (Some(50.0), Some(40.0), Some(61.0)));
        // 95th percentile of 20 values: no upper bound (needs n >= 72).
        let (_, _, h) = quantile_ci(&v[..20], 0.95, 0.95);
        assert_eq!(h, None);
    }

    #[test]
    fn binomial_bound_is_zero_for_rare_alarms() {
        // 300 trials at 3.9e-6: P(X >= 1) = 1.2e-3 < 1 %, so the bound is 0.
        assert_eq!(binomial_bound_99(300, 3.9e-6), 0);
        // 1000 trials at 1e-2: P(X <= 17) = 0.98617, P(X <= 18) = 0.99310
        // (exact binomial sums).
        assert_eq!(binomial_bound_99(1000, 1e-2), 18);
    }
}
