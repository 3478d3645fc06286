//! `raim replay --esq-mcusum`: the MCUSUM (SPEC §7) fed samples that are
//! not time-correlated (docs/ESQ.md).
//!
//! docs/MCRAIM.md records that the MCUSUM false-alarms on the clean real
//! files: its ARL0 assumes white parity vectors, and the real errors are
//! correlated over minutes. Here:
//!
//! 1. the correlation time of the parity vector is measured on the clean
//!    run: per epoch the whitened post-fit residual vector r_t (the parity
//!    vector mapped back to range space: same norm, basis-free), and
//!    rho(L) = sum_t <r_t, r_{t+L}> / sqrt(sum |r_t|^2 sum |r_{t+L}|^2) over
//!    the satellites common to both epochs; tau_c = the first lag with
//!    rho < 1/e (and the integrated time, sum of rho until it turns
//!    negative, for reference);
//! 2. the monitor (snapshot test + MCUSUM, `--mcusum` settings) runs on
//!    every epoch ("before") and on one epoch every M = round(tau_c / dt)
//!    ("after"), with the per-sample false-alarm budget multiplied by M
//!    (snapshot Pfa x M, MCUSUM ARL0 / M): the same nominal false-alarm
//!    rate per unit time, so the same nominal ARL0 in seconds;
//! 3. "split": the snapshot test alone on every epoch at its own share,
//!    and the combination on the decimated samples with its snapshot Pfa at
//!    the smallest allowed value (1e-9 per sample: at most +0.6 % of the
//!    budget), so that only the MCUSUM is decimated;
//! 4. "alone": the snapshot test alone on every epoch with the whole
//!    budget, the reference for what the MCUSUM adds;
//! 5. false alarms (alarms and exclusions before the onset) and the
//!    detection delay after the onset are printed for all four.
//!
//! Why the measured correlation time and not dT_e: dT_e = T / N* comes
//! from how the integrity risk spreads over the ARAIM fault modes (N* is
//! an effective count of modes), and from the arbitrary window T; it
//! contains no information on how fast the errors decorrelate. The
//! measured tau_c does, and it is what the white-noise ARL0 needs.

use std::io::Write;

use anyhow::{anyhow, Result};
use nalgebra::{DMatrix, DVector};
use raim_core::{Config, Decision, Epoch, Raim, SatId};

use super::esq::{setup, Setup};
use super::{ReplayArgs, REPLAY_CAPACITY};

/// Longest lag examined for the correlation time (epochs).
const MAX_LAG: usize = 60;

/// Whitened post-fit residuals of one epoch, by satellite.
fn whitened_residuals(s: &Setup, k: usize) -> Vec<(SatId, f64)> {
    let Some(e) = s.epochs.get(k) else {
        return Vec::new();
    };
    let obs = s.observations(e);
    let (sats, _) = s.araim_inputs(e, &obs);
    let mut systems: Vec<raim_core::System> = Vec::new();
    for a in &sats {
        if !systems.contains(&a.id.system) {
            systems.push(a.id.system);
        }
    }
    let m = 3 + systems.len();
    let n = sats.len();
    if n <= m {
        return Vec::new();
    }
    let mut g = DMatrix::<f64>::zeros(n, m);
    let mut y = DVector::<f64>::zeros(n);
    for (i, a) in sats.iter().enumerate() {
        let w = 1.0 / s.sigma_m(e.sats[i].elevation_rad, &obs[i]);
        for c in 0..3 {
            g[(i, c)] = a.g_enu[c] * w;
        }
        let j = systems.iter().position(|x| *x == a.id.system).unwrap_or(0);
        g[(i, 3 + j)] = w;
        y[i] = a.residual_m * w;
    }
    let Some(x) = (g.transpose() * &g)
        .try_inverse()
        .map(|inv| inv * g.transpose() * &y)
    else {
        return Vec::new();
    };
    let r = &y - &g * x;
    sats.iter().zip(r.iter()).map(|(a, v)| (a.id, *v)).collect()
}

/// rho(L) for L = 1..=MAX_LAG epochs; with `demean`, each satellite's
/// mean residual over the file is removed first (the fluctuating part).
pub fn parity_autocorrelation(s: &Setup, demean: bool) -> Vec<f64> {
    let mut res: Vec<Vec<(SatId, f64)>> = (0..s.epochs.len())
        .map(|k| whitened_residuals(s, k))
        .collect();
    if demean {
        let mut sums: std::collections::BTreeMap<SatId, (f64, usize)> = Default::default();
        for (id, v) in res.iter().flatten() {
            let e = sums.entry(*id).or_insert((0.0, 0));
            e.0 += v;
            e.1 += 1;
        }
        for (id, v) in res.iter_mut().flatten() {
            if let Some((s, n)) = sums.get(id) {
                *v -= s / *n as f64;
            }
        }
    }
    (1..=MAX_LAG)
        .map(|lag| {
            let (mut num, mut a2, mut b2) = (0.0, 0.0, 0.0);
            for t in 0..res.len().saturating_sub(lag) {
                for (id, a) in &res[t] {
                    if let Some((_, b)) = res[t + lag].iter().find(|(j, _)| j == id) {
                        num += a * b;
                        a2 += a * a;
                        b2 += b * b;
                    }
                }
            }
            num / (a2 * b2).sqrt()
        })
        .collect()
}

fn step_s(s: &Setup) -> f64 {
    let mut d: Vec<f64> = s
        .epochs
        .windows(2)
        .map(|w| w[1].time_gps_s - w[0].time_gps_s)
        .collect();
    d.sort_by(f64::total_cmp);
    d.get(d.len() / 2).copied().unwrap_or(30.0)
}

struct Outcome {
    samples: usize,
    false_alarms: usize,
    delay_s: Option<f64>,
}

fn monitor(s: &Setup, cfg: &Config, every: usize) -> Result<Outcome> {
    let mut raim = Box::new(Raim::<REPLAY_CAPACITY>::new());
    let mut out = Outcome {
        samples: 0,
        false_alarms: 0,
        delay_s: None,
    };
    for (k, e) in s.epochs.iter().enumerate() {
        if k % every != 0 {
            continue;
        }
        out.samples += 1;
        let obs = s.observations(e);
        let ep = Epoch::ranges(e.time_gps_s, &obs, e.reference_m);
        let Ok(r) = raim.process(cfg, &ep) else {
            continue;
        };
        let hit = matches!(r.decision, Decision::Alarm | Decision::Excluded);
        match s.onset_gps_s {
            Some(t0) if e.time_gps_s >= t0 - 1e-3 => {
                if hit && out.delay_s.is_none() {
                    out.delay_s = Some(e.time_gps_s - t0);
                }
            }
            _ => out.false_alarms += usize::from(hit),
        }
    }
    Ok(out)
}

/// The split variant: the snapshot test alone on every epoch (engine A,
/// `cfg_a`), the combination on one epoch in `every` (engine B, `cfg_b`,
/// whose own snapshot share is set to the smallest allowed Pfa, so that
/// it adds next to nothing); an epoch alarms when A does, or B on a sample.
fn monitor_split(s: &Setup, cfg_a: &Config, cfg_b: &Config, every: usize) -> Result<Outcome> {
    let mut a = Box::new(Raim::<REPLAY_CAPACITY>::new());
    let mut b = Box::new(Raim::<REPLAY_CAPACITY>::new());
    let mut out = Outcome {
        samples: 0,
        false_alarms: 0,
        delay_s: None,
    };
    let alarmed = |d: Decision| matches!(d, Decision::Alarm | Decision::Excluded);
    for (k, e) in s.epochs.iter().enumerate() {
        let obs = s.observations(e);
        let ep = Epoch::ranges(e.time_gps_s, &obs, e.reference_m);
        let mut hit = a.process(cfg_a, &ep).is_ok_and(|r| alarmed(r.decision));
        if k % every == 0 {
            out.samples += 1;
            hit |= b.process(cfg_b, &ep).is_ok_and(|r| alarmed(r.decision));
        }
        match s.onset_gps_s {
            Some(t0) if e.time_gps_s >= t0 - 1e-3 => {
                if hit && out.delay_s.is_none() {
                    out.delay_s = Some(e.time_gps_s - t0);
                }
            }
            _ => out.false_alarms += usize::from(hit),
        }
    }
    Ok(out)
}

pub fn run(args: &ReplayArgs, w: &mut impl Write) -> Result<()> {
    let s = setup(args)?;
    let mut cfg = s.cfg;
    if !cfg.mcusum.enabled {
        cfg = cfg.split_false_alarm_budget(0.5);
    }
    let dt = step_s(&s);
    // The correlation time comes from the clean data (no faults).
    let clean = Setup {
        epochs: s.epochs.clone(),
        plan: Default::default(),
        eph: Vec::new(),
        receiver_m: s.receiver_m,
        cfg: s.cfg,
        p_const: s.p_const,
        onset_gps_s: None,
    };
    let mut e_fold = None;
    for demean in [false, true] {
        let rho = parity_autocorrelation(&clean, demean);
        let fold = rho
            .iter()
            .position(|r| *r < (-1.0f64).exp())
            .map(|l| (l + 1) as f64 * dt);
        let integrated = dt * (1.0 + 2.0 * rho.iter().take_while(|r| **r > 0.0).sum::<f64>());
        writeln!(
            w,
            "parity-vector autocorrelation ({}, {} epochs, step {dt:.0} s): rho(1) {:.3} rho(2) {:.3} rho(5) {:.3} rho(10) {:.3} rho(20) {:.3}; 1/e at {}; integrated (1 + 2 sum rho) {integrated:.0} s",
            if demean { "per-satellite mean removed" } else { "raw" },
            s.epochs.len(),
            rho.first().copied().unwrap_or(f64::NAN),
            rho.get(1).copied().unwrap_or(f64::NAN),
            rho.get(4).copied().unwrap_or(f64::NAN),
            rho.get(9).copied().unwrap_or(f64::NAN),
            rho.get(19).copied().unwrap_or(f64::NAN),
            fold.map_or(format!("> {} s", MAX_LAG as f64 * dt), |t| format!("{t:.0} s"))
        )?;
        if demean {
            e_fold = fold;
        } else {
            // The raw vector (bias included) is what the MCUSUM accumulates;
            // its integrated time in samples is the variance inflation I of
            // a long sum, and the Gauss-Markov tau with that I at this step
            // is the `--mcusum-tau-s` it calls for.
            let inflation = integrated / dt;
            writeln!(
                w,
                "Gauss-Markov fit to the raw integrated time: inflation {inflation:.1} at step {dt:.0} s, tau {:.0} s (--mcusum-tau-s)",
                raim_core::sequential::mcusum::correlation_time_for_inflation_s(dt, inflation)
            )?;
        }
    }
    let interval = match args.esq.esq_decimate_s {
        Some(v) if v > 0.0 && v.is_finite() => v,
        Some(v) => return Err(anyhow!("--esq-decimate-s {v}: must be positive")),
        None => e_fold.unwrap_or(MAX_LAG as f64 * dt),
    };
    let m = ((interval / dt).round() as usize).max(1);
    let mut dec = cfg;
    dec.pfa = (cfg.pfa * m as f64).min(0.5);
    dec.mcusum.arl0 = (cfg.mcusum.arl0 / m as f64).max(1.0);
    dec.validate()
        .map_err(|e| anyhow!("decimated configuration (M = {m}): {e}"))?;
    let before = monitor(&s, &cfg, 1)?;
    let after = monitor(&s, &dec, m)?;
    // Split: snapshot every epoch at its own share, MCUSUM decimated.
    let mut snap_only = cfg;
    snap_only.mcusum.enabled = false;
    let mut mcusum_dec = dec;
    mcusum_dec.pfa = raim_core::config_bounds::PFA.min;
    mcusum_dec
        .validate()
        .map_err(|e| anyhow!("decimated MCUSUM configuration (M = {m}): {e}"))?;
    let split = monitor_split(&s, &snap_only, &mcusum_dec, m)?;
    // The snapshot test alone on every epoch with the whole budget: what
    // the MCUSUM adds is measured against it.
    let mut alone = cfg;
    alone.mcusum.enabled = false;
    alone.pfa = cfg.pfa + 1.0 / cfg.mcusum.arl0;
    let alone = monitor(&s, &alone, 1)?;
    writeln!(
        w,
        "nominal ARL0 {:.3e} s in both: before every {dt:.0} s (snapshot Pfa {:.3e}, MCUSUM ARL0 {:.3e} samples); after every {:.0} s (M = {m}: Pfa {:.3e}, ARL0 {:.3e} samples)",
        dt / (cfg.pfa + 1.0 / cfg.mcusum.arl0),
        cfg.pfa,
        cfg.mcusum.arl0,
        m as f64 * dt,
        dec.pfa,
        dec.mcusum.arl0,
    )?;
    for (name, o) in [
        ("before", &before),
        ("after ", &after),
        ("split ", &split),
        ("alone ", &alone),
    ] {
        writeln!(
            w,
            "  {name}: {} samples, false alarms {}, detection delay {}",
            o.samples,
            o.false_alarms,
            if s.onset_gps_s.is_some() {
                o.delay_s.map_or("never".into(), |d| format!("{d:.0} s"))
            } else {
                "- (no fault)".into()
            }
        )?;
    }
    Ok(())
}
