//! YUMA almanacs (GPS, and the same text form for Galileo) into
//! [`raim_nav::ephemeris::Kepler`] orbits (SPEC §14 "Almanac").
//!
//! A YUMA record is a `****` header line and thirteen `Key: value` lines:
//! ID, Health, Eccentricity, Time of Applicability (s), Orbital Inclination
//! (rad, the full inclination, not SEM's offset from 0.3 semicircles),
//! Rate of Right Ascen (rad/s), SQRT(A) (m^1/2), Right Ascen at Week or at
//! TOA (rad: Omega_0, the node at the week's start, as in the broadcast
//! ephemeris), Argument of Perigee (rad), Mean Anom (rad), Af0 (s), Af1
//! (s/s), week. The positions are the IS-GPS-200 Keplerian equations
//! without harmonic corrections (every correction term of the `Kepler`
//! zero), through the same `Kepler::state` the receiver uses.
//!
//! The week field is the 10-bit broadcast week (SPEC §14): it is resolved
//! into a full GPS week only with an explicit rollover count from the run
//! file (0 before 1999-08-22, 1 until 2019-04-07, 2 until 2038-11-21), and
//! refused without one: a silent guess would place the almanac 19.6 years
//! off. A week of 1024 or more is already a full week and refused with a
//! rollover count (an ambiguous file). Every error names the file and line.

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};
use raim_core::System;
use raim_nav::ephemeris::{Kepler, WEEK_S};

/// One satellite of an almanac: its orbit and where it was read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AlmanacSat {
    /// The orbit, `toe_sow_s` = the time of applicability.
    pub kepler: Kepler,
    /// The time of applicability as a full GPS week.
    pub week: u32,
    /// The file line of the record's ID.
    pub line: usize,
}

/// How a file's records become satellites.
#[derive(Debug, Clone, PartialEq)]
pub struct AlmanacSpec {
    /// The file.
    pub path: PathBuf,
    /// The constellation of every record.
    pub system: System,
    /// PRN = ID - `id_offset` (MAAST numbers its Galileo slots 75-98:
    /// offset 74 reads them as Galileo 1-24).
    pub id_offset: u32,
    /// GPS week rollovers to add to a 10-bit week field.
    pub week_rollovers: Option<u32>,
}

/// The healthy satellites of one almanac file, in file order, and the
/// PRNs of the records whose health word was not zero (left out).
#[derive(Debug, Clone, PartialEq)]
pub struct Almanac {
    /// Healthy satellites.
    pub sats: Vec<AlmanacSat>,
    /// PRNs with a non-zero health word.
    pub unhealthy: Vec<u8>,
}

/// A record's fields by `KEYS` slot: (line, value text).
type Fields = [Option<(usize, String)>; 13];

const KEYS: [&str; 13] = [
    "id",
    "health",
    "eccentricity",
    "time of applicability",
    "orbital inclination",
    "rate of right ascen",
    "sqrt(a)",
    "right ascen at",
    "argument of perigee",
    "mean anom",
    "af0",
    "af1",
    "week",
];

/// Reads `spec.path`.
///
/// # Errors
/// The file unreadable or without a record, a record missing a field or
/// with an unparsable one, a health word that is not a decimal number, a
/// 10-bit week without a rollover count, an ID outside 1..=63 after the
/// offset, a duplicate ID; each naming the file and line.
pub fn read(spec: &AlmanacSpec) -> Result<Almanac> {
    let text = std::fs::read_to_string(&spec.path)
        .map_err(|e| anyhow::anyhow!("{}: {e}", spec.path.display()))?;
    parse(&text, spec)
}

/// [`read`] on text already in memory (`spec.path` names it in errors).
///
/// # Errors
/// As [`read`].
pub fn parse(text: &str, spec: &AlmanacSpec) -> Result<Almanac> {
    let file = spec.path.display();
    let mut records: Vec<(usize, Fields)> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let t = raw.trim();
        if t.is_empty() {
            continue;
        }
        if t.starts_with("****") {
            records.push((line, Default::default()));
            continue;
        }
        let Some((key, value)) = t.split_once(':') else {
            bail!("{file}:{line}: expected `Key: value` or a `****` record header, found `{t}`");
        };
        let Some((_, fields)) = records.last_mut() else {
            bail!("{file}:{line}: `{key}` before the first `****` record header");
        };
        let k = key.trim().to_ascii_lowercase();
        let Some(slot) = KEYS.iter().position(|p| k.starts_with(p)) else {
            bail!("{file}:{line}: unknown YUMA field `{}`", key.trim());
        };
        if fields[slot].is_some() {
            bail!(
                "{file}:{line}: field `{}` given twice in one record",
                key.trim()
            );
        }
        fields[slot] = Some((line, value.trim().to_string()));
    }
    if records.is_empty() {
        bail!("{file}: no almanac record (an empty file, or no `****` header)");
    }
    let mut out = Almanac {
        sats: Vec::new(),
        unhealthy: Vec::new(),
    };
    let mut seen = [false; 64];
    for (header, fields) in &records {
        let get = |slot: usize| -> Result<(usize, &str)> {
            match &fields[slot] {
                Some((l, v)) => Ok((*l, v.as_str())),
                None => bail!("{file}:{header}: the record has no `{}` field", KEYS[slot]),
            }
        };
        let num = |slot: usize| -> Result<f64> {
            let (l, v) = get(slot)?;
            match v.parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(x),
                _ => bail!("{file}:{l}: `{}` is not a finite number: `{v}`", KEYS[slot]),
            }
        };
        let int = |slot: usize, what: &str| -> Result<(usize, u32)> {
            let (l, v) = get(slot)?;
            if v.is_empty() || !v.bytes().all(|b| b.is_ascii_digit()) {
                bail!("{file}:{l}: bad {what} `{v}` (expected decimal digits)");
            }
            match v.parse::<u32>() {
                Ok(x) => Ok((l, x)),
                Err(_) => bail!("{file}:{l}: bad {what} `{v}`"),
            }
        };
        let (id_line, id) = int(0, "ID")?;
        let prn = id
            .checked_sub(spec.id_offset)
            .filter(|p| (1..=63).contains(p))
            .ok_or_else(|| {
                anyhow::anyhow!(
                    "{file}:{id_line}: ID {id} minus the offset {} is not a PRN in 1..=63",
                    spec.id_offset
                )
            })?;
        let prn = prn as u8;
        if std::mem::replace(&mut seen[usize::from(prn)], true) {
            bail!("{file}:{id_line}: PRN {prn} (ID {id}) appears twice");
        }
        let (_, health) = int(1, "health word")?;
        let (week_line, week10) = int(12, "week")?;
        let week = full_week(&file.to_string(), week_line, week10, spec.week_rollovers)?;
        let toa_s = num(3)?;
        if !(0.0..WEEK_S).contains(&toa_s) {
            let (l, v) = get(3)?;
            bail!("{file}:{l}: time of applicability `{v}` s is outside the week [0, 604800)");
        }
        let e = num(2)?;
        if !(0.0..1.0).contains(&e) {
            let (l, v) = get(2)?;
            bail!("{file}:{l}: eccentricity `{v}` outside [0, 1)");
        }
        let sqrt_a = num(6)?;
        if sqrt_a <= 0.0 {
            let (l, v) = get(6)?;
            bail!("{file}:{l}: SQRT(A) `{v}` is not positive");
        }
        let kepler = orbit(
            spec.system,
            prn,
            week,
            toa_s,
            Elements {
                e,
                i0_rad: num(4)?,
                omega_dot_rad_s: num(5)?,
                sqrt_a_m05: sqrt_a,
                omega0_rad: num(7)?,
                omega_rad: num(8)?,
                m0_rad: num(9)?,
                af0_s: num(10)?,
                af1_s_s: num(11)?,
            },
            health,
        );
        if health != 0 {
            out.unhealthy.push(prn);
            continue;
        }
        out.sats.push(AlmanacSat {
            kepler,
            week,
            line: id_line,
        });
    }
    Ok(out)
}

/// An almanac's orbital elements (radians, SI units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Elements {
    /// Eccentricity.
    pub e: f64,
    /// Inclination (rad).
    pub i0_rad: f64,
    /// Rate of right ascension (rad/s).
    pub omega_dot_rad_s: f64,
    /// Square root of the semi-major axis (m^1/2).
    pub sqrt_a_m05: f64,
    /// Right ascension at the week's start, Omega_0 (rad).
    pub omega0_rad: f64,
    /// Argument of perigee (rad).
    pub omega_rad: f64,
    /// Mean anomaly at the time of applicability (rad).
    pub m0_rad: f64,
    /// Clock bias (s).
    pub af0_s: f64,
    /// Clock drift (s/s).
    pub af1_s_s: f64,
}

/// The `Kepler` orbit of an almanac record: `toe` = the time of
/// applicability, every harmonic correction zero.
pub fn orbit(system: System, prn: u8, week: u32, toa_s: f64, el: Elements, health: u32) -> Kepler {
    Kepler {
        system,
        prn,
        toc_gps_s: f64::from(week) * WEEK_S + toa_s,
        toe_sow_s: toa_s,
        af0_s: el.af0_s,
        af1_s_s: el.af1_s_s,
        af2_s_s2: 0.0,
        sqrt_a_m05: el.sqrt_a_m05,
        e: el.e,
        i0_rad: el.i0_rad,
        omega0_rad: el.omega0_rad,
        omega_rad: el.omega_rad,
        m0_rad: el.m0_rad,
        delta_n_rad_s: 0.0,
        omega_dot_rad_s: el.omega_dot_rad_s,
        idot_rad_s: 0.0,
        cuc_rad: 0.0,
        cus_rad: 0.0,
        crc_m: 0.0,
        crs_m: 0.0,
        cic_rad: 0.0,
        cis_rad: 0.0,
        group_delay_s: 0.0,
        group_delay_e5a_s: 0.0,
        health,
        iod: 0,
    }
}

/// The full GPS week of a 10-bit almanac week (as in YUMA records).
fn full_week(file: &str, line: usize, w: u32, rollovers: Option<u32>) -> Result<u32> {
    match (w, rollovers) {
        (w, Some(r)) if w < 1024 => Ok(w + 1024 * r),
        (w, None) if w < 1024 => bail!(
            "{file}:{line}: week {w} is a 10-bit broadcast week: the run file must say \
             how many 1024-week rollovers to add (`week_rollovers`: 0 before 1999-08-22, \
             1 until 2019-04-07, 2 until 2038-11-21)"
        ),
        (w, Some(_)) => {
            bail!("{file}:{line}: week {w} is already a full GPS week: remove `week_rollovers`")
        }
        (w, None) => Ok(w),
    }
}

/// One semicircle in radians (SEM's angular unit, IS-GPS-200).
const SEMICIRCLE_RAD: f64 = core::f64::consts::PI;
/// SEM's reference inclination (semicircles): i = 0.30 + the offset.
const SEM_I_REF: f64 = 0.30;

/// Reads a SEM almanac (`spec.path`).
///
/// # Errors
/// As [`parse_sem`].
pub fn read_sem(spec: &AlmanacSpec) -> Result<Almanac> {
    let text = std::fs::read_to_string(&spec.path)
        .map_err(|e| anyhow::anyhow!("{}: {e}", spec.path.display()))?;
    parse_sem(&text, spec)
}

/// A SEM almanac (the USCG NAVCEN format): a header line `N NAME` (the
/// record count), a line `WEEK TOA` (the 10-bit week and the time of
/// applicability, s), then N records of eight lines, blank lines between
/// them ignored: PRN; SVN; average URA number; eccentricity, inclination
/// offset from 0.30 semicircles, rate of right ascension (semicircles/s);
/// sqrt(A) (m^1/2), longitude of the orbital plane at the week's start
/// Omega_0 (semicircles), argument of perigee (semicircles); mean anomaly
/// (semicircles), af0 (s), af1 (s/s); health (0 healthy); configuration.
/// Semicircles are converted to radians by pi (IS-GPS-200), the
/// inclination is (0.30 + offset) semicircles. The same checks and
/// errors as YUMA's (file and line).
///
/// # Errors
/// A missing or unparsable header, a record cut short or with a line
/// that does not hold its numbers, a count that is not the header's, and
/// the YUMA reader's checks (week, PRN, duplicate, eccentricity, sqrt(A),
/// time of applicability).
pub fn parse_sem(text: &str, spec: &AlmanacSpec) -> Result<Almanac> {
    let file = spec.path.display().to_string();
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty());
    let mut next = |what: &str| -> Result<(usize, &str)> {
        lines
            .next()
            .ok_or_else(|| anyhow::anyhow!("{file}: the file ends where {what} was expected"))
    };
    let nums = |line: usize, t: &str, what: &str, n: usize| -> Result<Vec<f64>> {
        let v: Vec<f64> = t
            .split_whitespace()
            .map(str::parse::<f64>)
            .collect::<Result<_, _>>()
            .map_err(|_| {
                anyhow::anyhow!("{file}:{line}: {what}: `{t}` does not parse as numbers")
            })?;
        if v.len() != n || v.iter().any(|x| !x.is_finite()) {
            bail!("{file}:{line}: {what}: expected {n} finite numbers, found `{t}`");
        }
        Ok(v)
    };
    let int = |line: usize, t: &str, what: &str| -> Result<u32> {
        t.parse::<u32>().map_err(|_| {
            anyhow::anyhow!("{file}:{line}: bad {what} `{t}` (expected decimal digits)")
        })
    };
    let (l1, t1) = next("the header `N NAME`")?;
    let count = match t1.split_whitespace().next().map(str::parse::<usize>) {
        Some(Ok(n)) if n > 0 => n,
        _ => bail!("{file}:{l1}: expected the header `N NAME` (N the record count), found `{t1}`"),
    };
    let (l2, t2) = next("the line `WEEK TOA`")?;
    let wt: Vec<&str> = t2.split_whitespace().collect();
    let [w, toa] = wt.as_slice() else {
        bail!("{file}:{l2}: expected `WEEK TOA`, found `{t2}`");
    };
    let week = full_week(&file, l2, int(l2, w, "week")?, spec.week_rollovers)?;
    let toa_s = nums(l2, toa, "time of applicability", 1)?[0];
    if !(0.0..WEEK_S).contains(&toa_s) {
        bail!("{file}:{l2}: time of applicability `{toa}` s is outside the week [0, 604800)");
    }
    let mut out = Almanac {
        sats: Vec::new(),
        unhealthy: Vec::new(),
    };
    let mut seen = [false; 64];
    let mut records = 0usize;
    while let Some((id_line, t)) = lines.next() {
        records += 1;
        if records > count {
            bail!("{file}:{id_line}: more records than the header's {count}");
        }
        let id = int(id_line, t, "PRN")?;
        let prn = id
            .checked_sub(spec.id_offset)
            .filter(|p| (1..=63).contains(p))
            .ok_or_else(|| {
                anyhow::anyhow!(
                    "{file}:{id_line}: ID {id} minus the offset {} is not a PRN in 1..=63",
                    spec.id_offset
                )
            })? as u8;
        if std::mem::replace(&mut seen[usize::from(prn)], true) {
            bail!("{file}:{id_line}: PRN {prn} (ID {id}) appears twice");
        }
        let mut take = |what: &str| -> Result<(usize, &str)> {
            lines.next().ok_or_else(|| {
                anyhow::anyhow!("{file}:{id_line}: the record of PRN {id} ends before its {what}")
            })
        };
        let (l, t) = take("SVN")?;
        int(l, t, "SVN")?;
        let (l, t) = take("URA number")?;
        nums(l, t, "URA number", 1)?;
        let (l, t) = take("eccentricity line")?;
        let a = nums(
            l,
            t,
            "eccentricity, inclination offset, rate of right ascension",
            3,
        )?;
        if !(0.0..1.0).contains(&a[0]) {
            bail!("{file}:{l}: eccentricity `{}` outside [0, 1)", a[0]);
        }
        let (l, t) = take("sqrt(A) line")?;
        let b = nums(
            l,
            t,
            "sqrt(A), longitude of the orbital plane, argument of perigee",
            3,
        )?;
        if b[0] <= 0.0 {
            bail!("{file}:{l}: sqrt(A) `{}` is not positive", b[0]);
        }
        let (l, t) = take("mean anomaly line")?;
        let c = nums(l, t, "mean anomaly, af0, af1", 3)?;
        let (l, t) = take("health")?;
        let health = int(l, t, "health word")?;
        let (l, t) = take("configuration")?;
        int(l, t, "configuration")?;
        let kepler = orbit(
            spec.system,
            prn,
            week,
            toa_s,
            Elements {
                e: a[0],
                i0_rad: (SEM_I_REF + a[1]) * SEMICIRCLE_RAD,
                omega_dot_rad_s: a[2] * SEMICIRCLE_RAD,
                sqrt_a_m05: b[0],
                omega0_rad: b[1] * SEMICIRCLE_RAD,
                omega_rad: b[2] * SEMICIRCLE_RAD,
                m0_rad: c[0] * SEMICIRCLE_RAD,
                af0_s: c[1],
                af1_s_s: c[2],
            },
            health,
        );
        if health != 0 {
            out.unhealthy.push(prn);
            continue;
        }
        out.sats.push(AlmanacSat {
            kepler,
            week,
            line: id_line,
        });
    }
    if records != count {
        bail!("{file}:{l1}: the header announces {count} records, the file holds {records}");
    }
    Ok(out)
}

/// The path as given, or relative to `base` (the run file's directory).
pub fn resolve(base: &Path, p: &Path) -> PathBuf {
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        base.join(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn data(name: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../../shared/data")
            .join(name)
    }

    fn spec(path: PathBuf, system: System, id_offset: u32) -> AlmanacSpec {
        AlmanacSpec {
            path,
            system,
            id_offset,
            week_rollovers: Some(0),
        }
    }

    /// The DO-229 almanac: 24 healthy satellites, PRN 1-24, circular
    /// orbits, week 703; at the time of applicability every satellite is
    /// at radius A = sqrt(A)^2 (e = 0) and its ECEF position equals the
    /// closed form of a circular orbit written out here independently:
    /// u = M0 + omega, Omega = Omega0 - omega_e toa (Omega-dot 0).
    ///
    /// Verifies: SPEC-14
    #[test]
    fn gps_mops_almanac_matches_circular_closed_form() {
        let alm = read(&spec(data("almanac_gps24_mops.yuma"), System::Gps, 0)).unwrap();
        assert_eq!(alm.sats.len(), 24);
        assert!(alm.unhealthy.is_empty());
        for (k, s) in alm.sats.iter().enumerate() {
            assert_eq!(usize::from(s.kepler.prn), k + 1);
            assert_eq!(s.week, 703);
            let kp = &s.kepler;
            let t = f64::from(s.week) * WEEK_S + kp.toe_sow_s;
            let p = kp.state(t).position_m;
            let a = kp.sqrt_a_m05 * kp.sqrt_a_m05;
            let u = kp.m0_rad + kp.omega_rad;
            let om = kp.omega0_rad - 7.292_115_146_7e-5 * kp.toe_sow_s;
            let (x, y) = (a * u.cos(), a * u.sin());
            let expect = [
                x * om.cos() - y * kp.i0_rad.cos() * om.sin(),
                x * om.sin() + y * kp.i0_rad.cos() * om.cos(),
                y * kp.i0_rad.sin(),
            ];
            for q in 0..3 {
                assert!((p[q] - expect[q]).abs() < 1e-6, "PRN {} axis {q}", kp.prn);
            }
            // 26,559.7 km: the GPS semi-major axis.
            assert!((a - 26_559_700.0).abs() < 1e3);
        }
    }

    /// MAAST's Galileo file: IDs 75-98 read as E01-E24 (offset 74).
    #[test]
    fn galileo_ids_map_to_prn_1_24() {
        let alm = read(&spec(data("almanac_galileo24.yuma"), System::Galileo, 74)).unwrap();
        let prns: Vec<u8> = alm.sats.iter().map(|s| s.kepler.prn).collect();
        assert_eq!(prns, (1..=24).collect::<Vec<u8>>());
        assert!(alm.sats.iter().all(|s| s.kepler.e == 1e-4));
        // Without the offset the IDs are not PRNs.
        let err = read(&spec(data("almanac_galileo24.yuma"), System::Galileo, 0)).unwrap_err();
        assert!(
            err.to_string().contains("almanac_galileo24.yuma:2:"),
            "{err}"
        );
    }

    fn gps_text() -> String {
        std::fs::read_to_string(data("almanac_gps24_mops.yuma")).unwrap()
    }

    fn parse_err(text: &str, rollovers: Option<u32>) -> String {
        let s = AlmanacSpec {
            path: PathBuf::from("alm.yuma"),
            system: System::Gps,
            id_offset: 0,
            week_rollovers: rollovers,
        };
        parse(text, &s).unwrap_err().to_string()
    }

    #[test]
    fn bad_input_names_file_and_line() {
        let text = gps_text();
        // Health word of PRN 02 (line 18) not a number.
        let bad = text.replacen(
            "Health:                     000",
            "Health:                     0x1",
            2,
        );
        let bad = bad.replacen(
            "Health:                     0x1",
            "Health:                     000",
            1,
        );
        assert_eq!(
            parse_err(&bad, Some(0)),
            "alm.yuma:18: bad health word `0x1` (expected decimal digits)"
        );
        // A 10-bit week without a rollover count: refused at the first week line.
        let e = parse_err(&text, None);
        assert!(
            e.starts_with("alm.yuma:14: week 703 is a 10-bit broadcast week"),
            "{e}"
        );
        // A full week with a rollover count: ambiguous.
        let full = text.replace(
            "week:                        703",
            "week:                        2407",
        );
        let e = parse_err(&full, Some(2));
        assert!(
            e.starts_with("alm.yuma:14: week 2407 is already a full GPS week"),
            "{e}"
        );
        assert_eq!(
            parse_err("", Some(0)),
            "alm.yuma: no almanac record (an empty file, or no `****` header)"
        );
        assert_eq!(
            parse_err("\n\n", Some(0)),
            "alm.yuma: no almanac record (an empty file, or no `****` header)"
        );
        let e = parse_err(
            &text.replacen(
                "Eccentricity:               0.0",
                "Eccentricity:               x",
                1,
            ),
            Some(0),
        );
        assert_eq!(e, "alm.yuma:4: `eccentricity` is not a finite number: `x`");
        let dup = text.replacen(
            "ID:                         02",
            "ID:                         01",
            1,
        );
        assert_eq!(
            parse_err(&dup, Some(0)),
            "alm.yuma:17: PRN 1 (ID 1) appears twice"
        );
        let missing = text.replacen("Mean Anom(rad):             0.4679681510E+001\n", "", 1);
        assert_eq!(
            parse_err(&missing, Some(0)),
            "alm.yuma:1: the record has no `mean anom` field"
        );
    }

    /// Rollovers are explicit: 1 adds 1024 weeks; a non-zero health word
    /// leaves the satellite out and reports it.
    ///
    /// Verifies: SPEC-14
    #[test]
    fn rollover_and_health() {
        let text = gps_text();
        let s = AlmanacSpec {
            path: PathBuf::from("alm.yuma"),
            system: System::Gps,
            id_offset: 0,
            week_rollovers: Some(2),
        };
        let a = parse(&text, &s).unwrap();
        assert!(a.sats.iter().all(|x| x.week == 703 + 2048));
        let sick = text.replacen(
            "Health:                     000",
            "Health:                     063",
            1,
        );
        let a = parse(&sick, &s).unwrap();
        assert_eq!(a.unhealthy, vec![1]);
        assert_eq!(a.sats.len(), 23);
    }

    /// The DO-229 almanac written out as a SEM file here (semicircles =
    /// rad / pi, the inclination as its offset from 0.30 semicircles, the
    /// USCG NAVCEN layout) reads back as the same satellites: every ECEF
    /// position at the time of applicability and 6 h and 12 h later within
    /// 1e-6 m of the YUMA one. A non-zero health word leaves its satellite
    /// out.
    ///
    /// Verifies: TOOL-AVAIL-SEM
    #[test]
    fn sem_written_from_yuma_gives_the_same_orbits() {
        let yuma = read(&spec(data("almanac_gps24_mops.yuma"), System::Gps, 0)).unwrap();
        let pi = core::f64::consts::PI;
        let toa = yuma.sats[0].kepler.toe_sow_s;
        let mut sem = format!(
            "{} DO229.ALM\n {} {}\n\n",
            yuma.sats.len(),
            yuma.sats[0].week % 1024,
            toa
        );
        for s in &yuma.sats {
            let k = &s.kepler;
            let health = u32::from(k.prn == 7) * 63;
            sem.push_str(&format!(
                "{}\n{}\n0\n {:.15E} {:.15E} {:.15E}\n {:.15E} {:.15E} {:.15E}\n {:.15E} {:.15E} {:.15E}\n{}\n11\n\n",
                k.prn, k.prn + 30,
                k.e, k.i0_rad / pi - 0.30, k.omega_dot_rad_s / pi,
                k.sqrt_a_m05, k.omega0_rad / pi, k.omega_rad / pi,
                k.m0_rad / pi, k.af0_s, k.af1_s_s,
                health
            ));
        }
        let got = parse_sem(&sem, &spec(PathBuf::from("alm.sem"), System::Gps, 0)).unwrap();
        assert_eq!(got.unhealthy, vec![7]);
        assert_eq!(got.sats.len(), 23);
        for g in &got.sats {
            let y = yuma
                .sats
                .iter()
                .find(|y| y.kepler.prn == g.kepler.prn)
                .unwrap();
            assert_eq!(g.week, y.week);
            for dt in [0.0, 21_600.0, 43_200.0] {
                let t = f64::from(y.week) * WEEK_S + toa + dt;
                let (a, b) = (g.kepler.state(t).position_m, y.kepler.state(t).position_m);
                for q in 0..3 {
                    assert!(
                        (a[q] - b[q]).abs() < 1e-6,
                        "PRN {} dt {dt} axis {q}: {} vs {}",
                        g.kepler.prn,
                        a[q],
                        b[q]
                    );
                }
            }
        }
        // Bad SEM input names the file and line.
        let err = |t: &str| {
            parse_sem(t, &spec(PathBuf::from("alm.sem"), System::Gps, 0))
                .unwrap_err()
                .to_string()
        };
        let lines: Vec<&str> = sem.lines().collect();
        let cut = lines[..lines.len() - 3].join("\n");
        assert!(err(&cut).contains("alm.sem:"), "{}", err(&cut));
        assert!(
            err(&cut).contains("ends before its health"),
            "{}",
            err(&cut)
        );
        let bad = sem.replacen(" 0.000000000000000E0 ", " x ", 1);
        assert!(bad != sem);
        assert!(
            err(&bad).starts_with("alm.sem:7: eccentricity, inclination offset"),
            "{}",
            err(&bad)
        );
        let short = sem.replacen("24 DO229", "25 DO229", 1);
        assert_eq!(
            err(&short),
            "alm.sem:1: the header announces 25 records, the file holds 24"
        );
        assert!(
            err("").contains("the file ends where the header"),
            "{}",
            err("")
        );
        let wk = parse_sem(
            &sem,
            &AlmanacSpec {
                week_rollovers: None,
                ..spec(PathBuf::from("alm.sem"), System::Gps, 0)
            },
        )
        .unwrap_err();
        assert!(
            wk.to_string()
                .starts_with("alm.sem:2: week 703 is a 10-bit broadcast week"),
            "{wk}"
        );
    }
}
