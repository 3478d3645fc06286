//! The end-of-run table: epochs solved, alarms, correct and wrong
//! exclusions, missed detections, detection delay, and the position error
//! (median and max) of the epochs a user would have used.

use serde::Serialize;

use super::record::EpochRecord;

#[derive(Debug, Clone, Default, Serialize, PartialEq)]
pub struct Summary {
    pub epochs: usize,
    /// Epochs with a usable position (ok, excluded, unavailable).
    pub solved: usize,
    pub ok: usize,
    pub excluded: usize,
    pub unavailable: usize,
    pub alarms: usize,
    /// Epochs the core refused (typed error, e.g. too few satellites).
    pub errors: usize,
    /// Epochs carrying an injected step/ramp.
    pub faulted_epochs: usize,
    /// Faulted epochs where exactly the faulted satellites were excluded.
    pub correct_exclusions: usize,
    /// Faulted epochs where some, not all, faulted satellites were excluded
    /// and nothing else.
    pub partial_exclusions: usize,
    /// Epochs where a satellite without an injected fault was excluded
    /// (on clean epochs too).
    pub wrong_exclusions: usize,
    /// Faulted epochs with neither an alarm nor an exclusion.
    pub missed_detections: usize,
    /// Alarms on epochs without an injected fault.
    pub false_alarms: usize,
    /// Exclusions on epochs without an injected fault.
    pub false_exclusions: usize,
    /// First alarm or exclusion of a faulted satellite after the fault
    /// started, s, and the injected bias then, m.
    pub detection_delay_s: Option<f64>,
    pub bias_at_detection_m: Option<f64>,
    /// Horizontal / vertical error of the usable epochs, m.
    pub error_h_median_m: f64,
    pub error_h_max_m: f64,
    pub error_v_median_m: f64,
    pub error_v_max_m: f64,
    /// Usable epochs whose error exceeds its protection level (H or V).
    pub misleading: usize,
    /// Mean of D^2/dof over the solved epochs without an injected fault:
    /// 1 if the sigma model matches the real residuals (SPEC §3).
    pub clean_d2_per_dof_mean: f64,
    /// Largest D^2/T^2 over those epochs (an alarm is >= 1).
    pub clean_d2_over_t2_max: f64,
    /// Epochs without an injected fault that the monitor tested (every
    /// decision but a core error): the trials of the false-alarm count.
    pub clean_tested: usize,
    /// Of those, the epochs with an alarm or an exclusion in force: each is
    /// a false event against the per-epoch false-alarm allocation.
    pub clean_false_events: usize,
    /// The total false-alarm allocation per epoch (`--pfa`; with `--mcusum`
    /// the snapshot test's and the MCUSUM's shares together).
    pub pfa_per_epoch: f64,
    /// The binomial 99 % bound of `clean_false_events` under
    /// `pfa_per_epoch`: the least b with P(Bin(clean_tested, pfa) <= b) >=
    /// 0.99, assuming independent epochs.
    pub false_event_bound_99: u64,
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Summarise `records`; `fault_start_gps_s` is the earliest start of a
/// satellite fault (for the detection delay), `pfa_per_epoch` the total
/// false-alarm allocation the clean epochs' events are held to.
pub fn summarise(
    records: &[EpochRecord],
    fault_start_gps_s: Option<f64>,
    pfa_per_epoch: f64,
) -> Summary {
    let mut s = Summary {
        epochs: records.len(),
        pfa_per_epoch,
        ..Default::default()
    };
    let mut eh = Vec::new();
    let mut ev = Vec::new();
    let mut ratio = Vec::new();
    let mut worst = f64::NAN;
    for r in records {
        if r.faulted_ids.is_empty() && r.initial_dof > 0 && r.initial_statistic.is_finite() {
            ratio.push(r.initial_statistic / f64::from(r.initial_dof));
            worst = worst.max(r.initial_statistic / r.initial_threshold);
        }
        match r.decision.as_str() {
            "ok" => s.ok += 1,
            "excluded" => s.excluded += 1,
            "unavailable" => s.unavailable += 1,
            "alarm" => s.alarms += 1,
            _ => s.errors += 1,
        }
        if r.usable() {
            s.solved += 1;
            if let (Some(h), Some(v)) = (r.error_h_m, r.error_v_m) {
                eh.push(h);
                ev.push(v);
                if h > r.hpl_m || v > r.vpl_m {
                    s.misleading += 1;
                }
            }
        }
        let excluded = &r.excluded_ids;
        let wrong = excluded.iter().any(|id| !r.faulted_ids.contains(id));
        if wrong {
            s.wrong_exclusions += 1;
        }
        if r.faulted_ids.is_empty() {
            let alarm = r.decision == "alarm";
            s.false_alarms += usize::from(alarm);
            s.false_exclusions += usize::from(!excluded.is_empty());
            if r.decision != "error" {
                s.clean_tested += 1;
                s.clean_false_events += usize::from(alarm || !excluded.is_empty());
            }
            continue;
        }
        s.faulted_epochs += 1;
        if !wrong && !excluded.is_empty() {
            if r.faulted_ids.iter().all(|id| excluded.contains(id)) {
                s.correct_exclusions += 1;
            } else {
                s.partial_exclusions += 1;
            }
        }
        if excluded.is_empty() && r.usable() {
            s.missed_detections += 1;
        }
    }
    if let Some(start) = fault_start_gps_s {
        let first = records
            .iter()
            .filter(|r| r.time_gps_s >= start && !r.faulted_ids.is_empty())
            .find(|r| {
                r.decision == "alarm" || r.excluded_ids.iter().any(|id| r.faulted_ids.contains(id))
            });
        if let Some(r) = first {
            s.detection_delay_s = Some(r.time_gps_s - start);
            s.bias_at_detection_m = r.faulted.first().map(|(_, b)| *b);
        }
    }
    s.false_event_bound_99 = super::stats::binomial_bound_99(s.clean_tested, pfa_per_epoch);
    s.clean_d2_per_dof_mean = ratio.iter().sum::<f64>() / ratio.len().max(1) as f64;
    s.clean_d2_over_t2_max = worst;
    s.error_h_median_m = median(eh.clone());
    s.error_h_max_m = eh.iter().copied().fold(f64::NAN, f64::max);
    s.error_v_median_m = median(ev.clone());
    s.error_v_max_m = ev.iter().copied().fold(f64::NAN, f64::max);
    s
}

impl Summary {
    /// A readable table.
    pub fn table(&self) -> String {
        let opt =
            |v: Option<f64>, unit: &str| v.map_or("-".to_string(), |v| format!("{v:.1} {unit}"));
        let rows = [
            ("epochs", self.epochs.to_string()),
            ("solved (usable position)", self.solved.to_string()),
            (
                "  ok / excluded / unavailable",
                format!("{} / {} / {}", self.ok, self.excluded, self.unavailable),
            ),
            ("alarms", self.alarms.to_string()),
            ("core errors (no solution)", self.errors.to_string()),
            ("faulted epochs", self.faulted_epochs.to_string()),
            ("correct exclusions", self.correct_exclusions.to_string()),
            ("partial exclusions", self.partial_exclusions.to_string()),
            ("wrong exclusions", self.wrong_exclusions.to_string()),
            ("missed detections", self.missed_detections.to_string()),
            ("false alarms (clean epochs)", self.false_alarms.to_string()),
            (
                "false exclusions (clean epochs)",
                self.false_exclusions.to_string(),
            ),
            ("detection delay", opt(self.detection_delay_s, "s")),
            ("bias at detection", opt(self.bias_at_detection_m, "m")),
            (
                "horizontal error median / max",
                format!("{:.2} / {:.2} m", self.error_h_median_m, self.error_h_max_m),
            ),
            (
                "vertical error median / max",
                format!("{:.2} / {:.2} m", self.error_v_median_m, self.error_v_max_m),
            ),
            ("error > PL while usable", self.misleading.to_string()),
            (
                "fault-free D2/dof mean (1 = sigma fits)",
                format!("{:.3}", self.clean_d2_per_dof_mean),
            ),
            (
                "fault-free max D2/T2",
                format!("{:.3}", self.clean_d2_over_t2_max),
            ),
            (
                "clean false events / 99 % bound",
                format!(
                    "{} in {} tested clean epochs / {} (binomial, Pfa {:e} per epoch): {}",
                    self.clean_false_events,
                    self.clean_tested,
                    self.false_event_bound_99,
                    self.pfa_per_epoch,
                    if self.clean_false_events as u64 <= self.false_event_bound_99 {
                        "within"
                    } else {
                        "above"
                    }
                ),
            ),
        ];
        let mut out = String::new();
        for (k, v) in rows {
            out.push_str(&format!("{k:<34} {v}\n"));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use raim_core::{SatId, System};

    fn rec(
        t: f64,
        decision: &str,
        excluded: &[u8],
        faulted: &[(u8, f64)],
        err_h: f64,
    ) -> EpochRecord {
        let g = |p: u8| SatId::new(System::Gps, p);
        let mut r = EpochRecord::from_error(t, 8, &[], &"x");
        r.decision = decision.into();
        r.error = None;
        r.initial_statistic = 1.0;
        r.initial_threshold = 30.0;
        r.initial_dof = 2;
        r.excluded_ids = excluded.iter().map(|&p| g(p)).collect();
        r.faulted_ids = faulted.iter().map(|&(p, _)| g(p)).collect();
        r.faulted = faulted
            .iter()
            .map(|&(p, b)| (g(p).to_string(), b))
            .collect();
        r.error_h_m = Some(err_h);
        r.error_v_m = Some(0.0);
        r.hpl_m = 10.0;
        r.vpl_m = 10.0;
        r
    }

    /// Every class of the table, counted on a hand-made run.
    #[test]
    fn counts_each_class() {
        let recs = vec![
            rec(0.0, "ok", &[], &[], 1.0),
            rec(30.0, "excluded", &[3], &[], 2.0), // false + wrong exclusion
            rec(60.0, "ok", &[], &[(24, 5.0)], 3.0), // missed
            rec(90.0, "alarm", &[], &[(24, 8.0)], 50.0), // detected (alarm), not usable
            rec(120.0, "excluded", &[24], &[(24, 11.0)], 4.0), // correct
            rec(150.0, "excluded", &[24], &[(24, 14.0), (11, 14.0)], 20.0), // partial, error > HPL
        ];
        let s = summarise(&recs, Some(60.0), 1e-2);
        assert_eq!(
            (s.epochs, s.solved, s.ok, s.excluded, s.alarms),
            (6, 5, 2, 3, 1)
        );
        assert_eq!(
            (s.faulted_epochs, s.correct_exclusions, s.partial_exclusions),
            (4, 1, 1)
        );
        assert_eq!((s.wrong_exclusions, s.missed_detections), (1, 1));
        assert_eq!((s.false_alarms, s.false_exclusions), (0, 1));
        // Two clean epochs tested, one with an exclusion; Bin(2, 1e-2):
        // P(X <= 0) = 0.9801 < 0.99 <= P(X <= 1), so the bound is 1.
        assert_eq!(
            (s.clean_tested, s.clean_false_events, s.false_event_bound_99),
            (2, 1, 1)
        );
        assert_eq!(
            (s.detection_delay_s, s.bias_at_detection_m),
            (Some(30.0), Some(8.0))
        );
        // Usable errors 1, 2, 3, 4, 20: median 3, max 20; one exceeds its PL.
        assert_eq!(
            (s.error_h_median_m, s.error_h_max_m, s.misleading),
            (3.0, 20.0, 1)
        );
    }
}
