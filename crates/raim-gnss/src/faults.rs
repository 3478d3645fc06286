//! Deterministic, seeded fault injection on corrected pseudoranges (SPEC §1:
//! the fault vector f of z = Hx + e + f).
//!
//! Kinds: a step or a ramp on one or several satellites or on a whole
//! constellation, a receiver clock jump (common to every satellite: the
//! clock absorbs it, so it must *not* alarm), and extra heavy-tailed noise
//! (Student-t or Laplace). Faults come from the command line
//! (`step:G24:50@00:20:00`) or a TOML scenario file. Noise draws are a pure
//! function of (seed, epoch time, satellite), so a run is reproducible
//! whatever the satellite selection or the order of processing.

use std::path::Path;

use raim_core::{RangeObservation, SatId, System};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StudentT};
use serde::Deserialize;

use crate::error::GnssError;
use crate::{parse_sat, parse_system, time};

/// Which satellites a fault touches.
#[derive(Debug, Clone, PartialEq)]
pub enum Target {
    Sats(Vec<SatId>),
    System(System),
    All,
}

impl Target {
    fn hits(&self, id: SatId) -> bool {
        match self {
            Target::Sats(v) => v.contains(&id),
            Target::System(s) => id.system == *s,
            Target::All => true,
        }
    }

    fn parse(s: &str) -> Result<Self, GnssError> {
        let s = s.trim();
        if s.eq_ignore_ascii_case("all") {
            return Ok(Target::All);
        }
        if s.len() == 1 {
            let c = s
                .chars()
                .next()
                .ok_or_else(|| GnssError::BadSatellite(s.into()))?;
            return Ok(Target::System(parse_system(c)?));
        }
        let sats = s.split('+').map(parse_sat).collect::<Result<Vec<_>, _>>()?;
        Ok(Target::Sats(sats))
    }
}

/// Heavy-tailed noise distributions, unit scale.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Noise {
    /// Student-t with `dof` degrees of freedom (variance dof/(dof-2)).
    StudentT { dof: f64 },
    /// Laplace (double exponential), scale 1: variance 2.
    Laplace,
}

impl Noise {
    fn parse(s: &str) -> Result<Self, GnssError> {
        let bad = |d: &str| GnssError::BadFault {
            spec: s.into(),
            detail: d.into(),
        };
        let s = s.trim().to_ascii_lowercase();
        if s == "laplace" {
            return Ok(Noise::Laplace);
        }
        let dof: f64 = s
            .strip_prefix('t')
            .ok_or_else(|| bad("noise is laplace or tN (Student-t, N dof)"))?
            .parse()
            .map_err(|_| bad("Student-t dof is a number"))?;
        if !(dof > 0.0 && dof.is_finite()) {
            return Err(bad("Student-t dof must be positive"));
        }
        Ok(Noise::StudentT { dof })
    }

    fn draw(&self, rng: &mut ChaCha8Rng) -> f64 {
        match *self {
            Noise::StudentT { dof } => StudentT::new(dof).map(|d| d.sample(rng)).unwrap_or(0.0),
            Noise::Laplace => {
                // Inverse CDF of the Laplace distribution from U(-1/2, 1/2).
                let u: f64 = rand::Rng::random::<f64>(rng) - 0.5;
                -u.signum() * (1.0 - 2.0 * u.abs()).max(f64::MIN_POSITIVE).ln()
            }
        }
    }
}

/// What a fault does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FaultKind {
    /// A constant bias from the start time, m.
    Step { bias_m: f64 },
    /// A bias growing linearly from zero at the start time, m/s.
    Ramp { rate_m_s: f64 },
    /// A receiver clock jump: every satellite shifts by the same amount.
    ClockJump { jump_m: f64 },
    /// Extra noise `scale_m` x a unit draw of `noise`, per satellite and epoch.
    Noise { noise: Noise, scale_m: f64 },
}

/// One fault, with its times resolved to GPS seconds.
#[derive(Debug, Clone, PartialEq)]
pub struct Fault {
    pub target: Target,
    pub kind: FaultKind,
    pub start_gps_s: f64,
    pub end_gps_s: Option<f64>,
}

impl Fault {
    fn active(&self, t: f64) -> bool {
        t >= self.start_gps_s && self.end_gps_s.is_none_or(|e| t < e)
    }

    /// Whether this fault is a satellite fault the monitor should find
    /// (steps and ramps; a clock jump and noise are not).
    pub fn is_satellite_fault(&self) -> bool {
        matches!(self.kind, FaultKind::Step { .. } | FaultKind::Ramp { .. })
    }
}

/// A set of faults and the seed of their noise.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FaultPlan {
    pub faults: Vec<Fault>,
    pub seed: u64,
}

/// What was injected at one epoch.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Injected {
    /// Satellites carrying an active step or ramp, with the bias, m.
    pub faulted: Vec<(SatId, f64)>,
    /// The clock jump applied to every satellite, m.
    pub clock_m: f64,
}

/// SplitMix64: a well-mixed 64-bit seed from (seed, time, satellite).
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

impl FaultPlan {
    pub fn is_empty(&self) -> bool {
        self.faults.is_empty()
    }

    /// Add the active faults to `sats` at GPS time `t`; returns what was done.
    pub fn apply(&self, t_gps_s: f64, sats: &mut [RangeObservation]) -> Injected {
        let mut out = Injected::default();
        for s in sats.iter_mut() {
            let mut bias = 0.0;
            let mut sat_fault = false;
            for (k, f) in self.faults.iter().enumerate() {
                if !f.active(t_gps_s) {
                    continue;
                }
                match f.kind {
                    FaultKind::ClockJump { jump_m } => s.pseudorange_m += jump_m,
                    _ if !f.target.hits(s.id) => {}
                    FaultKind::Step { bias_m } => {
                        bias += bias_m;
                        sat_fault = true;
                    }
                    FaultKind::Ramp { rate_m_s } => {
                        bias += rate_m_s * (t_gps_s - f.start_gps_s);
                        sat_fault = true;
                    }
                    FaultKind::Noise { noise, scale_m } => {
                        let key = mix(self.seed)
                            ^ mix((t_gps_s * 1000.0).round() as u64)
                            ^ mix(((s.id.system.index() as u64) << 8 | s.id.prn as u64)
                                + ((k as u64) << 16));
                        let mut rng = ChaCha8Rng::seed_from_u64(mix(key));
                        s.pseudorange_m += scale_m * noise.draw(&mut rng);
                    }
                }
            }
            // A ramp at its first epoch adds nothing: not (yet) a fault.
            if sat_fault && bias != 0.0 {
                s.pseudorange_m += bias;
                out.faulted.push((s.id, bias));
            }
        }
        out.clock_m = self
            .faults
            .iter()
            .filter(|f| f.active(t_gps_s))
            .filter_map(|f| match f.kind {
                FaultKind::ClockJump { jump_m } => Some(jump_m),
                _ => None,
            })
            .sum();
        out
    }

    /// Parse one command-line fault:
    /// `step:TARGET:BIAS_M@START[..END]`, `ramp:TARGET:RATE_M_S@START[..END]`,
    /// `clock:JUMP_M@START[..END]`, `noise:TARGET:DIST:SCALE_M[@START[..END]]`,
    /// TARGET = `G24`, `G15+G28`, a system letter (`E`) or `all`;
    /// DIST = `laplace` or `tN` (Student-t, N dof); times as in [`time::resolve`].
    pub fn parse_cli(spec: &str, first_gps_s: f64) -> Result<Fault, GnssError> {
        let bad = |d: &str| GnssError::BadFault {
            spec: spec.into(),
            detail: d.into(),
        };
        let (body, when) = match spec.split_once('@') {
            Some((b, w)) => (b, Some(w)),
            None => (spec, None),
        };
        let (start_gps_s, end_gps_s) = match when {
            Some(w) => {
                let (s, e) = match w.split_once("..") {
                    Some((s, e)) => (s, Some(e)),
                    None => (w, None),
                };
                (
                    time::resolve(s, first_gps_s)?,
                    e.map(|e| time::resolve(e, first_gps_s)).transpose()?,
                )
            }
            None => (f64::NEG_INFINITY, None),
        };
        let parts: Vec<&str> = body.split(':').collect();
        let num = |s: &str| -> Result<f64, GnssError> {
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| bad("not a number"))
        };
        let (target, kind) = match parts.as_slice() {
            ["step", t, b] => (Target::parse(t)?, FaultKind::Step { bias_m: num(b)? }),
            ["ramp", t, r] => (Target::parse(t)?, FaultKind::Ramp { rate_m_s: num(r)? }),
            ["clock", j] => (Target::All, FaultKind::ClockJump { jump_m: num(j)? }),
            ["noise", t, d, s] => {
                let scale_m = num(s)?;
                if scale_m < 0.0 {
                    return Err(bad("noise scale must be >= 0"));
                }
                (
                    Target::parse(t)?,
                    FaultKind::Noise {
                        noise: Noise::parse(d)?,
                        scale_m,
                    },
                )
            }
            _ => {
                return Err(bad(
                    "expected step:T:B@t, ramp:T:R@t, clock:J@t or noise:T:DIST:S[@t]",
                ))
            }
        };
        if matches!(
            kind,
            FaultKind::Step { .. } | FaultKind::Ramp { .. } | FaultKind::ClockJump { .. }
        ) && when.is_none()
        {
            return Err(bad("a step, ramp or clock jump needs @START"));
        }
        Ok(Fault {
            target,
            kind,
            start_gps_s,
            end_gps_s,
        })
    }
}

/// A scenario file (TOML):
///
/// ```toml
/// seed = 7
/// [[fault]]
/// kind = "step"          # step | ramp | clock | noise
/// target = "G15+G28"     # a satellite, several joined by +, a system letter, or "all"
/// value = 50.0           # step/clock: m; ramp: m/s; noise: scale m
/// start = "01:00:00"     # time of day of the first epoch's day, or "+S"
/// end = "02:00:00"       # optional
/// noise = "t3"           # noise only: t<dof> or laplace
/// ```
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    #[serde(default)]
    pub seed: u64,
    #[serde(default)]
    pub fault: Vec<ScenarioFault>,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioFault {
    pub kind: String,
    #[serde(default)]
    pub target: Option<String>,
    pub value: f64,
    #[serde(default)]
    pub start: Option<String>,
    #[serde(default)]
    pub end: Option<String>,
    #[serde(default)]
    pub noise: Option<String>,
}

impl Scenario {
    pub fn load(path: &Path) -> Result<Self, GnssError> {
        let text = std::fs::read_to_string(path).map_err(|e| GnssError::Scenario {
            path: path.into(),
            detail: e.to_string(),
        })?;
        toml::from_str(&text).map_err(|e| GnssError::Scenario {
            path: path.into(),
            detail: e.to_string(),
        })
    }

    /// The faults as command-line specs, parsed the same way.
    pub fn plan(&self, first_gps_s: f64) -> Result<FaultPlan, GnssError> {
        let mut faults = Vec::new();
        for f in &self.fault {
            let target = f.target.clone().unwrap_or_else(|| "all".into());
            let when = match (&f.start, &f.end) {
                (Some(s), Some(e)) => format!("@{s}..{e}"),
                (Some(s), None) => format!("@{s}"),
                (None, _) => String::new(),
            };
            let spec = match f.kind.as_str() {
                "clock" => format!("clock:{}{when}", f.value),
                "noise" => format!(
                    "noise:{target}:{}:{}{when}",
                    f.noise.as_deref().unwrap_or("t3"),
                    f.value
                ),
                k => format!("{k}:{target}:{}{when}", f.value),
            };
            faults.push(FaultPlan::parse_cli(&spec, first_gps_s)?);
        }
        Ok(FaultPlan {
            faults,
            seed: self.seed,
        })
    }
}

/// A constellation-wide fault (ARAIM; the ADD's constellation
/// fault mode): every satellite of `system` in `sats` gets the range error
///
///   b_i = common_m - u_i . shift_ecef_m,
///
/// u_i the unit line of sight from `receiver_ecef_m` to satellite i. The
/// second term is what a common error of the constellation's orbits (an
/// Earth-orientation or frame error: every satellite displaced so that the
/// constellation alone puts the receiver at `receiver + shift`) does to the
/// ranges, to first order (|shift|^2 / range). The uniform `common_m` is a
/// constellation clock/time-offset error; on its own it is absorbed by the
/// constellation's clock column and moves no position. Returns each
/// satellite touched with its bias (m). Additive: the fault plan's
/// `step:E:..` (a uniform step) is unchanged.
pub fn constellation_bias(
    sats: &mut [RangeObservation],
    system: System,
    receiver_ecef_m: [f64; 3],
    common_m: f64,
    shift_ecef_m: [f64; 3],
) -> Vec<(SatId, f64)> {
    let mut out = Vec::new();
    for s in sats.iter_mut().filter(|s| s.id.system == system) {
        let d = [
            s.position_m[0] - receiver_ecef_m[0],
            s.position_m[1] - receiver_ecef_m[1],
            s.position_m[2] - receiver_ecef_m[2],
        ];
        let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        if r.is_nan() || r <= 0.0 {
            continue;
        }
        let along = (d[0] * shift_ecef_m[0] + d[1] * shift_ecef_m[1] + d[2] * shift_ecef_m[2]) / r;
        let b = common_m - along;
        s.pseudorange_m += b;
        out.push((s.id, b));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const T0: f64 = 1_000.0 * time::DAY_S;

    fn sats() -> Vec<RangeObservation> {
        ["G15", "G28", "E11", "C07"]
            .iter()
            .map(|s| RangeObservation {
                id: parse_sat(s).unwrap(),
                pseudorange_m: 2e7,
                position_m: [0.0; 3],
                sigma_m: None,
            })
            .collect()
    }

    /// Verifies: TOOL-FAULTS
    #[test]
    fn step_and_ramp_on_named_satellites() {
        let plan = FaultPlan {
            faults: vec![
                FaultPlan::parse_cli("step:G15+G28:50@01:00:00", T0).unwrap(),
                FaultPlan::parse_cli("ramp:E11:0.1@01:00:00..01:10:00", T0).unwrap(),
            ],
            seed: 0,
        };
        let mut s = sats();
        let inj = plan.apply(T0 + 3599.0, &mut s);
        assert!(inj.faulted.is_empty() && s.iter().all(|o| o.pseudorange_m == 2e7));
        let mut s = sats();
        let inj = plan.apply(T0 + 3600.0 + 180.0, &mut s);
        assert_eq!(s[0].pseudorange_m - 2e7, 50.0);
        assert_eq!(s[1].pseudorange_m - 2e7, 50.0);
        // 0.1 m/s for 180 s = 18 m.
        assert!((s[2].pseudorange_m - 2e7 - 18.0).abs() < 1e-9);
        assert_eq!(s[3].pseudorange_m, 2e7);
        assert_eq!(inj.faulted.len(), 3);
        // The ramp ends at 01:10:00.
        let mut s = sats();
        plan.apply(T0 + 4200.0, &mut s);
        assert_eq!(s[2].pseudorange_m, 2e7);
    }

    #[test]
    fn constellation_bias_and_clock_jump() {
        let plan = FaultPlan {
            faults: vec![
                FaultPlan::parse_cli("step:G:20@+0", T0).unwrap(),
                FaultPlan::parse_cli("clock:300@+60", T0).unwrap(),
            ],
            seed: 0,
        };
        let mut s = sats();
        let inj = plan.apply(T0 + 60.0, &mut s);
        let d: Vec<f64> = s.iter().map(|o| o.pseudorange_m - 2e7).collect();
        assert_eq!(d, vec![320.0, 320.0, 300.0, 300.0]);
        assert_eq!(inj.clock_m, 300.0);
        assert_eq!(inj.faulted.len(), 2);
    }

    /// Noise is a pure function of (seed, time, satellite): the same for
    /// the same key, different for another seed; and its spread matches
    /// the distribution: Laplace variance 2 (4th moment 24), Student-t(5)
    /// variance 5/3 (4th moment 3 nu^2/((nu-2)(nu-4)) = 25). Tolerance: 4
    /// standard errors of the sample variance, sqrt((mu4 - var^2)/n).
    #[test]
    fn noise_is_deterministic_and_has_the_right_spread() {
        const N: usize = 10_000;
        for (dist, var, mu4) in [("laplace", 2.0f64, 24.0f64), ("t5", 5.0 / 3.0, 25.0)] {
            let plan = FaultPlan {
                faults: vec![FaultPlan::parse_cli(&format!("noise:all:{dist}:1"), T0).unwrap()],
                seed: 42,
            };
            let draw = |t: f64, seed: u64| {
                let p = FaultPlan {
                    seed,
                    ..plan.clone()
                };
                let mut s = sats();
                p.apply(t, &mut s);
                s[0].pseudorange_m - 2e7
            };
            assert_eq!(draw(T0, 42), draw(T0, 42));
            assert_ne!(draw(T0, 42), draw(T0, 43));
            let v: Vec<f64> = (0..N).map(|i| draw(T0 + i as f64, 42)).collect();
            let mean = v.iter().sum::<f64>() / N as f64;
            let variance = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (N - 1) as f64;
            let tol_mean = 4.0 * (var / N as f64).sqrt();
            let tol_var = 4.0 * ((mu4 - var * var) / N as f64).sqrt();
            assert!(mean.abs() < tol_mean, "{dist} mean {mean}");
            assert!(
                (variance - var).abs() < tol_var,
                "{dist} var {variance} vs {var} (tol {tol_var})"
            );
        }
    }

    #[test]
    fn scenario_file_matches_cli() {
        let text = r#"
            seed = 7
            [[fault]]
            kind = "step"
            target = "G15+G28"
            value = 50.0
            start = "01:00:00"
            [[fault]]
            kind = "noise"
            target = "E"
            value = 1.5
            noise = "laplace"
        "#;
        let sc: Scenario = toml::from_str(text).unwrap();
        let plan = sc.plan(T0).unwrap();
        assert_eq!(plan.seed, 7);
        assert_eq!(
            plan.faults[0],
            FaultPlan::parse_cli("step:G15+G28:50@01:00:00", T0).unwrap()
        );
        assert_eq!(
            plan.faults[1].kind,
            FaultKind::Noise {
                noise: Noise::Laplace,
                scale_m: 1.5
            }
        );
        assert!(toml::from_str::<Scenario>("[[fault]]\nkind='step'\nvalue=1\nbogus=2").is_err());
    }

    /// Verifies: TOOL-FAULTS
    #[test]
    fn bad_specs_are_typed_errors() {
        for s in [
            "step:G24:50",
            "jump:G24:1@00:00",
            "step:X9:1@00:00",
            "noise:G:q:1",
            "step:G24:abc@00:00",
        ] {
            assert!(FaultPlan::parse_cli(s, T0).is_err(), "{s}");
        }
    }

    /// `constellation_bias` against the exact range change: the biased
    /// ranges of the constellation are the ranges from the shifted receiver
    /// (to |shift|^2 / range), plus the common part; other systems untouched.
    #[test]
    fn constellation_bias_is_the_range_change_of_a_shift() {
        let rx = [3_512_000.0, 778_000.0, 5_248_000.0];
        let shift = [12.0, -7.0, 20.0];
        let mk = |system, prn, p: [f64; 3]| RangeObservation {
            id: SatId { system, prn },
            pseudorange_m: 0.0,
            position_m: p,
            sigma_m: None,
        };
        let pos = [
            [15_000_000.0, 5_000_000.0, 20_000_000.0],
            [5_000_000.0, -12_000_000.0, 22_000_000.0],
            [20_000_000.0, 9_000_000.0, 15_000_000.0],
        ];
        let range = |a: [f64; 3], b: [f64; 3]| {
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
        };
        let mut sats: Vec<_> = pos
            .iter()
            .enumerate()
            .map(|(k, p)| mk(System::Galileo, k as u8 + 1, *p))
            .chain([mk(System::Gps, 3, pos[0])])
            .collect();
        let hit = constellation_bias(&mut sats, System::Galileo, rx, 2.5, shift);
        assert_eq!(hit.len(), 3);
        let moved = [rx[0] + shift[0], rx[1] + shift[1], rx[2] + shift[2]];
        for (s, p) in sats.iter().zip(pos.iter()).take(3) {
            let exact = range(*p, moved) - range(*p, rx) + 2.5;
            // |shift|^2 / range: 6e-4 m^2 / 2e7 m.
            assert!(
                (s.pseudorange_m - exact).abs() < 1e-4,
                "{}",
                s.pseudorange_m - exact
            );
        }
        assert_eq!(sats[3].pseudorange_m, 0.0);
    }
}

/// An ephemeris-like fault seen by one receiver (ESQ/PCA tests):
/// the broadcast orbit of a satellite at `sat_m` (ECEF) is wrong by
/// `radial_m` along its radial direction, so its range to the receiver at
/// `receiver_m` is off by the projection of that error on the line of
/// sight, radial_m (r_sat . los) with unit vectors. It differs per
/// satellite (0.97-1.0 of `radial_m` for a ground receiver, since a
/// satellite sees the Earth within about 14 degrees of nadir). Returns the
/// pseudorange error, m.
pub fn ephemeris_radial_error_m(sat_m: [f64; 3], receiver_m: [f64; 3], radial_m: f64) -> f64 {
    let r = (sat_m[0].powi(2) + sat_m[1].powi(2) + sat_m[2].powi(2)).sqrt();
    let d = [
        sat_m[0] - receiver_m[0],
        sat_m[1] - receiver_m[1],
        sat_m[2] - receiver_m[2],
    ];
    let n = (d[0].powi(2) + d[1].powi(2) + d[2].powi(2)).sqrt();
    if !(r > 0.0 && n > 0.0) {
        return 0.0;
    }
    radial_m * (sat_m[0] * d[0] + sat_m[1] * d[1] + sat_m[2] * d[2]) / (r * n)
}

#[cfg(test)]
mod ephemeris_tests {
    use super::ephemeris_radial_error_m;

    #[test]
    fn zenith_is_the_full_error_and_the_edge_of_the_earth_less() {
        // Satellite straight above: the whole radial error.
        let rx = [6_378_137.0, 0.0, 0.0];
        let sat = [26_560_000.0, 0.0, 0.0];
        assert!((ephemeris_radial_error_m(sat, rx, 10.0) - 10.0).abs() < 1e-12);
        // Satellite at the receiver's horizon: cos of the nadir angle
        // sin(nadir) = R_e / r.
        let r = 26_560_000.0f64;
        let re = 6_378_137.0f64;
        // Horizon point: the line of sight is tangent to the Earth at rx.
        let x = re;
        let y = (r * r - re * re).sqrt();
        let got = ephemeris_radial_error_m([x, y, 0.0], rx, 10.0);
        let expect = 10.0 * (1.0 - (re / r).powi(2)).sqrt();
        assert!((got - expect).abs() < 1e-9, "{got} {expect}");
    }
}
