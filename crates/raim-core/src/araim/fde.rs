//! ARAIM exclusion, after a failed solution-separation test.
//!
//! Candidates, in two stages: first the single-event modes (each
//! satellite, each constellation); then, only when none of those is
//! consistent, the multi-event modes of the all-in-view list (satellite
//! pairs, satellite + constellation, ...: every monitored mode with two or
//! more events). Only monitorable modes are candidates. Each candidate
//! subset is processed as an epoch of its own (its own fault modes, K_fa,
//! thresholds), and it is *consistent* when every one of its own tests
//! passes. Decision, on the consistent candidates of the stage that found
//! any:
//! - none in either stage: alarm (`NoCandidate`);
//! - the consistent candidates all contain one of them (e.g. satellite G5
//!   and the GPS constellation, which contains G5; or the pair {G5, E11}
//!   and {G5} + Galileo): exclude that smallest one, since every other
//!   consistent explanation removes it too;
//! - otherwise two consistent candidates that do not nest: the data
//!   cannot tell them apart, alarm (`Ambiguous`), never a silent pick.
//!
//! Why stages and not all candidates at once: a single fault leaves every
//! pair that holds the faulty satellite consistent too (they nest), but
//! also, by chance, a pair that does not (they do not nest: a needless
//! alarm); and the multi-event search costs about the square of the
//! single-event one. A multi-event exclusion is looked for only when no
//! single event explains the data.
//!
//! Work budget ([`FdeBudget`]): the search processes each candidate
//! subset as an epoch of its own, so its cost grows with the number of
//! candidates it processes (stage 1's, then stage 2's). A caller with a
//! deadline (the device, whose watchdog resets a unit that overruns)
//! gives the maximum number of candidates; the number a stage needs is
//! known before the stage starts (its monitorable modes), so a stage that
//! would take the total beyond the budget is not started and the outcome
//! is the alarm `BudgetExceeded`: never a pass, never a partial search
//! that could pick a wrong candidate. It is returned exactly when the
//! unlimited search would process more candidates than the budget, and
//! otherwise the outcome is the unlimited one (test
//! `budget_limited_fde_is_the_unlimited_one_or_budget_exceeded`). The
//! host's default, [`Araim::fde`], is unlimited.
//!
//! After an exclusion of E, the protection levels are those of the
//! remaining subset with its fault modes re-enumerated on it (its own
//! priors, thresholds and K_fa; the scratch engine's output), with the
//! exclusion risk in the integrity budget (docs/ARAIM.md, "Exclusion
//! risk"): per axis q, PL_q^(E) solves
//!
//!   2 Q((PL - b_q^(E)) / sigma_q^(E))
//!     + sum_{k in modes(E)} p_k Q((PL - T_k,q^(E) - b_q^(E,k)) / sigma_q^(E,k))
//!   = (1 / N_ex) PHMI_q (1 - P_unmon^(E) / (PHMI_VERT + PHMI_HOR)),
//!
//! N_ex the number of exclusions the FDE could have made: the monitorable
//! modes of the all-in-view list, single-event and multi-event alike (each
//! a candidate of one of the stages; with no multi-event modes, as at
//! P_sat 1e-5, the single-event ones only). Which
//! candidate passes is decided by the noise as much as by the fault: a
//! wrong exclusion is one of these outcomes. Each outcome gets 1 / N_ex of
//! the budget, so their union, P(HMI, some exclusion) <= sum_E P(HMI, E
//! excluded), stays within PHMI_q whichever one the FDE returns. Each term
//! bounds its outcome with unconditional priors: an all-in-view fault mode j
//! leaves, in the subset, the mode j \ E, whose prior on the subset is the
//! sum of p_j over the excluded satellites' states (the re-enumeration).

use super::{Araim, AraimConfig, AraimError, AraimSat, Ism, ModeStatus};
use crate::real::Real;

/// Why an exclusion was not made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FdeAlarm {
    /// No candidate subset (single- or multi-event) passes all its own
    /// tests.
    NoCandidate,
    /// Two consistent candidates (mode indices) that do not nest.
    Ambiguous {
        /// The first candidate's mode index.
        first: usize,
        /// The second candidate's mode index.
        second: usize,
    },
    /// The search would process more candidate subsets than the budget
    /// allows: `candidates` is the number through the stage that was not
    /// started (stage 1's, or stage 1's plus stage 2's), `budget` the
    /// maximum. Nothing was excluded.
    BudgetExceeded {
        /// Candidates through the stage not started.
        candidates: usize,
        /// The maximum allowed.
        budget: usize,
    },
}

/// The work the FDE may do: the maximum number of candidate subsets it
/// processes (module doc, "Work budget"). The final run of the chosen
/// subset (with its PLs) is not counted: it is one more subset.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FdeBudget {
    /// Largest number of exclusion candidates (subset ARAIM runs) per epoch.
    pub max_candidates: usize,
}

impl FdeBudget {
    /// No limit (the host's default).
    pub const UNLIMITED: Self = Self {
        max_candidates: usize::MAX,
    };
}

/// The outcome of ARAIM FDE. (After an alarm the scratch engine holds
/// the last candidate's tests only, marked `PlNotSolved { axis: 0 }`.)
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FdeDecision {
    /// The all-in-view test passed: nothing to exclude.
    NoFault,
    /// The mode `mode` (index into the all-in-view output's modes) was
    /// excluded: satellites `sats` (bit i = input satellite i, including
    /// those of excluded constellations) and constellations `consts`. The
    /// scratch engine holds the subset's output (PLs, EMT, availability).
    Excluded {
        /// Index of the excluded mode in the all-in-view output's modes.
        mode: usize,
        /// Excluded satellites, bit i = input satellite i.
        sats: u64,
        /// Excluded constellations, bit c = constellation index c.
        consts: u8,
    },
    /// No exclusion restores integrity: the integrity alarm and its cause.
    Alarm(FdeAlarm),
}

/// The satellites a mode removes (its satellites and every satellite of
/// its constellations).
fn removed_sats<T: Real>(sats: &[AraimSat<T>], ev_sats: u64, consts: u8) -> u64 {
    let mut m = ev_sats;
    for (i, s) in sats.iter().enumerate().take(64) {
        if consts & (1u8 << s.id.system.index()) != 0 {
            m |= 1u64 << i;
        }
    }
    m
}

/// The number of events (satellites and constellations) of a mode.
fn events_of<T>(mode: &super::FaultMode<T>) -> u32 {
    mode.events.sats.count_ones() + mode.events.consts.count_ones()
}

/// The satellites of `sats` not in `removed` into `buf` (their count) and
/// the ISM's P_const restricted to the constellations left.
fn subset_of<T: Real, const N: usize>(
    ism: &Ism,
    sats: &[AraimSat<T>],
    removed: u64,
    buf: &mut [AraimSat<T>; N],
) -> (usize, Ism) {
    let mut n = 0;
    let mut sub_ism = Ism::default();
    for (i, s) in sats.iter().enumerate() {
        if i < 64 && removed & (1u64 << i) != 0 {
            continue;
        }
        if let Some(slot) = buf.get_mut(n) {
            *slot = *s;
            n += 1;
        }
        let j = s.id.system.index();
        if let (Some(dst), Some(src)) = (sub_ism.p_const.get_mut(j), ism.p_const.get(j)) {
            *dst = *src;
        }
    }
    (n, sub_ism)
}

/// The two stages of the candidate search.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Stage {
    Single,
    Multi,
}

/// A consistent candidate: its mode's index and constellation events, and
/// the satellites it removes.
#[derive(Clone, Copy)]
struct Candidate {
    mode: usize,
    consts: u8,
    removed: u64,
}

/// The consistent candidates of one stage, folded as they come (no list:
/// a stage may hold up to K of them). A candidate contained in all the
/// others is the one whose removed set equals their intersection.
#[derive(Default)]
struct Found {
    /// The first consistent candidate (mode index, removed satellites).
    first: Option<(usize, u64)>,
    /// The second one, and the first that does not nest with `first`.
    second: Option<usize>,
    clash: Option<usize>,
    /// The intersection of all the removed sets.
    meet: u64,
    /// The candidate with the fewest removed satellites (the first such).
    smallest: Option<Candidate>,
}

impl Found {
    fn add(&mut self, candidate: Candidate) {
        let Candidate {
            mode: k, removed, ..
        } = candidate;
        match self.first {
            None => {
                self.first = Some((k, removed));
                self.meet = removed;
            }
            Some((_, c)) => {
                if self.second.is_none() {
                    self.second = Some(k);
                }
                if self.clash.is_none() && removed & c != c && removed & c != removed {
                    self.clash = Some(k);
                }
                self.meet &= removed;
            }
        }
        if self
            .smallest
            .is_none_or(|s| removed.count_ones() < s.removed.count_ones())
        {
            self.smallest = Some(candidate);
        }
    }

    /// The candidate to exclude, or the alarm.
    fn decide(&self) -> Result<Candidate, FdeAlarm> {
        let Some((k0, _)) = self.first else {
            return Err(FdeAlarm::NoCandidate);
        };
        match self.smallest {
            Some(c) if c.removed == self.meet => Ok(c),
            _ => Err(FdeAlarm::Ambiguous {
                first: k0,
                second: self.clash.or(self.second).unwrap_or(k0),
            }),
        }
    }
}

impl<T: Real, const N: usize, const K: usize> Araim<T, N, K> {
    /// The output of the last `process`.
    pub fn output(&self) -> &super::AraimOutput<T, K> {
        &self.out
    }

    /// Runs the exclusion logic of the module doc on the epoch last
    /// processed by `self` (same `cfg`, `ism`, `sats`), without a work
    /// limit. `scratch` is used for the candidate subsets; after
    /// `Excluded` it holds the chosen subset's output.
    pub fn fde(
        &self,
        cfg: &AraimConfig,
        ism: &Ism,
        sats: &[AraimSat<T>],
        scratch: &mut Araim<T, N, K>,
    ) -> Result<FdeDecision, AraimError> {
        self.fde_within(cfg, ism, sats, scratch, FdeBudget::UNLIMITED)
    }

    /// [`Self::fde`] within `budget`: the alarm `BudgetExceeded` when the
    /// search would process more candidates than the budget (module doc,
    /// "Work budget"), otherwise the same outcome.
    pub fn fde_within(
        &self,
        cfg: &AraimConfig,
        ism: &Ism,
        sats: &[AraimSat<T>],
        scratch: &mut Araim<T, N, K>,
        budget: FdeBudget,
    ) -> Result<FdeDecision, AraimError> {
        if self.out.detection_passed {
            return Ok(FdeDecision::NoFault);
        }
        // The candidate subsets use this engine's estimator.
        scratch.estimator = self.estimator;
        let mut subset = [AraimSat::<T>::default(); N];
        let (n_single, n_multi) = self.candidate_counts();
        let n_ex = n_single + n_multi;
        // Stage 1, the single-event candidates; stage 2, only when no
        // single event explains the data, the multi-event ones.
        let mut found = Found::default();
        for stage in [Stage::Single, Stage::Multi] {
            // The candidates processed once this stage is done; a stage
            // that would exceed the budget is not started.
            let through = match stage {
                Stage::Single => n_single,
                Stage::Multi => n_ex,
            };
            if through > budget.max_candidates {
                return Ok(FdeDecision::Alarm(FdeAlarm::BudgetExceeded {
                    candidates: through,
                    budget: budget.max_candidates,
                }));
            }
            for (k, mode) in self.out.modes.iter().enumerate() {
                let ev = mode.events;
                let single = events_of(mode) == 1;
                if mode.status != ModeStatus::Monitored || single != (stage == Stage::Single) {
                    continue;
                }
                let removed = removed_sats(sats, ev.sats, ev.consts);
                if self.consistent(cfg, ism, sats, removed, &mut subset, scratch, None)? {
                    found.add(Candidate {
                        mode: k,
                        consts: ev.consts,
                        removed,
                    });
                }
            }
            if found.first.is_some() {
                break;
            }
        }
        let chosen = match found.decide() {
            Ok(c) => c,
            Err(alarm) => return Ok(FdeDecision::Alarm(alarm)),
        };
        // Leave the chosen subset's output in the scratch engine, its PLs
        // with the exclusion risk: 1 / N_ex of the budget (module doc).
        let share = 1.0 / n_ex.max(1) as f64;
        self.consistent(
            cfg,
            ism,
            sats,
            chosen.removed,
            &mut subset,
            scratch,
            Some(share),
        )?;
        Ok(FdeDecision::Excluded {
            mode: chosen.mode,
            sats: chosen.removed,
            consts: chosen.consts,
        })
    }

    /// N_ex's two parts: the monitored single-event and multi-event modes
    /// of the last `process`, every candidate the search could return
    /// (module doc, "Exclusion risk").
    fn candidate_counts(&self) -> (usize, usize) {
        let (mut n_single, mut n_multi) = (0usize, 0usize);
        for mode in self.out.modes.iter() {
            if mode.status == ModeStatus::Monitored {
                match events_of(mode) {
                    1 => n_single += 1,
                    _ => n_multi += 1,
                }
            }
        }
        (n_single, n_multi)
    }

    /// Availability with exclusion (issue 36, docs/AVAILABILITY.md): the
    /// output the epoch last processed by `self` (same `cfg`, `ism`,
    /// `sats`) would have after excluding the events of its mode `k`,
    /// computed in `scratch` exactly as [`Self::fde`] leaves an `Excluded`
    /// subset: the subset processed as an epoch of its own, its PLs at the
    /// exclusion-risk share 1 / N_ex (module doc), whatever the
    /// residuals. `Ok(None)` when mode `k` is not a monitored mode or its
    /// subset cannot be processed (too few satellites, singular).
    ///
    /// # Errors
    /// The engine's refusal of the subset for any other cause.
    pub fn after_excluding<'s>(
        &self,
        cfg: &AraimConfig,
        ism: &Ism,
        sats: &[AraimSat<T>],
        k: usize,
        scratch: &'s mut Araim<T, N, K>,
    ) -> Result<Option<&'s super::AraimOutput<T, K>>, AraimError> {
        let Some(mode) = self.out.modes.get(k) else {
            return Ok(None);
        };
        if mode.status != ModeStatus::Monitored {
            return Ok(None);
        }
        let removed = removed_sats(sats, mode.events.sats, mode.events.consts);
        let (n_single, n_multi) = self.candidate_counts();
        let share = 1.0 / (n_single + n_multi).max(1) as f64;
        // The subset uses this engine's estimator.
        scratch.estimator = self.estimator;
        let mut buf = [AraimSat::<T>::default(); N];
        let (n, sub_ism) = subset_of(ism, sats, removed, &mut buf);
        let Some(subset) = buf.get(..n) else {
            return Ok(None);
        };
        match scratch.process_scaled(cfg, &sub_ism, subset, share) {
            Ok(out) => Ok(Some(out)),
            Err(AraimError::TooFewSatellites { .. } | AraimError::RankDeficient { .. }) => Ok(None),
            Err(e) => Err(e),
        }
    }

    /// Processes the subset without `removed` in `scratch`, with its PLs at
    /// the budget share `share`, or its tests only (`None`: the candidate
    /// search needs no PLs); true when it is valid and passes all its own
    /// tests.
    #[allow(clippy::too_many_arguments)]
    fn consistent(
        &self,
        cfg: &AraimConfig,
        ism: &Ism,
        sats: &[AraimSat<T>],
        removed: u64,
        buf: &mut [AraimSat<T>; N],
        scratch: &mut Araim<T, N, K>,
        share: Option<f64>,
    ) -> Result<bool, AraimError> {
        let (n, sub_ism) = subset_of(ism, sats, removed, buf);
        let Some(subset) = buf.get(..n) else {
            return Ok(false);
        };
        let result = match share {
            Some(share) => scratch.process_scaled(cfg, &sub_ism, subset, share),
            None => scratch.process_tests_only(cfg, &sub_ism, subset),
        };
        match result {
            Ok(out) => Ok(out.detection_passed && out.n_monitored > 0),
            // Too few satellites or a singular subset: not a candidate.
            Err(AraimError::TooFewSatellites { .. } | AraimError::RankDeficient { .. }) => {
                Ok(false)
            }
            Err(e) => Err(e),
        }
    }
}
