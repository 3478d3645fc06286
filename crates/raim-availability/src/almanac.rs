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
        let week = match (week10, spec.week_rollovers) {
            (w, Some(r)) if w < 1024 => w + 1024 * r,
            (w, None) if w < 1024 => bail!(
                "{file}:{week_line}: week {w} is a 10-bit broadcast week: the run file must say \
                 how many 1024-week rollovers to add (`week_rollovers`: 0 before 1999-08-22, \
                 1 until 2019-04-07, 2 until 2038-11-21)"
            ),
            (w, Some(_)) => bail!(
                "{file}:{week_line}: week {w} is already a full GPS week: remove `week_rollovers`"
            ),
            (w, None) => w,
        };
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
        let kepler = Kepler {
            system: spec.system,
            prn,
            toc_gps_s: f64::from(week) * WEEK_S + toa_s,
            toe_sow_s: toa_s,
            af0_s: num(10)?,
            af1_s_s: num(11)?,
            af2_s_s2: 0.0,
            sqrt_a_m05: sqrt_a,
            e,
            i0_rad: num(4)?,
            omega0_rad: num(7)?,
            omega_rad: num(8)?,
            m0_rad: num(9)?,
            delta_n_rad_s: 0.0,
            omega_dot_rad_s: num(5)?,
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
        };
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
}
