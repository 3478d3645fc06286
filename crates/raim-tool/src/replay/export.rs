//! The replay's standard solution files (docs/FORMATS.md, "Solution
//! files"): an RTKLIB-compatible `.pos` with the integrity columns after
//! RTKLIB's, a CSV with a header, KML and GPX tracks whose points carry the
//! decision and the excluded satellites, and the NMEA stream.

use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

use anyhow::{anyhow, Result};
use raim_core::frames::ecef_to_geodetic;

use super::record::EpochRecord;

/// Days from 1970-01-01 to the GPS time origin 1980-01-06.
const GPS_EPOCH_UNIX_DAYS: i64 = 3657;
const DAY_S: f64 = 86_400.0;

/// Proleptic Gregorian date of a day count from 1970-01-01 (H. Hinnant's
/// `civil_from_days`).
fn civil_from_days(z: i64) -> (i64, u32, u32) {
    let z = z + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    (yoe + era * 400 + i64::from(m <= 2), m, d)
}

/// Calendar date and time of seconds counted from a day-0 origin:
/// (year, month, day, hour, minute, seconds) with millisecond rounding.
fn calendar(days0: i64, s: f64) -> (i64, u32, u32, u32, u32, f64) {
    let ms = (s * 1000.0).round();
    let day = (ms / (DAY_S * 1000.0)).floor();
    let in_day_s = (ms - day * DAY_S * 1000.0) / 1000.0;
    let (y, mo, d) = civil_from_days(days0 + day as i64);
    let h = (in_day_s / 3600.0).floor();
    let mi = ((in_day_s - h * 3600.0) / 60.0).floor();
    (
        y,
        mo,
        d,
        h as u32,
        mi as u32,
        in_day_s - h * 3600.0 - mi * 60.0,
    )
}

/// GPS time as RTKLIB writes it: `2005/04/02 00:00:30.000`.
pub fn gpst_text(t_gps_s: f64) -> String {
    let (y, mo, d, h, mi, s) = calendar(GPS_EPOCH_UNIX_DAYS, t_gps_s);
    format!("{y:04}/{mo:02}/{d:02} {h:02}:{mi:02}:{s:06.3}")
}

/// UTC as ISO 8601 (`2005-04-01T23:59:47Z`), from the GPS time through the
/// leap seconds (GPX and KML times are UTC).
pub fn utc_iso(t_gps_s: f64) -> String {
    let unix = raim_gnss::time::unix_utc_s(t_gps_s);
    let (y, mo, d, h, mi, s) = calendar(0, unix);
    format!(
        "{y:04}-{mo:02}-{d:02}T{h:02}:{mi:02}:{:02}Z",
        s.round() as u32
    )
}

/// Latitude and longitude in degrees, ellipsoidal height in m.
fn llh(r: &EpochRecord) -> Option<(f64, f64, f64)> {
    r.position_ecef_m.map(|p| {
        let g = ecef_to_geodetic(p);
        (g.lat_rad.to_degrees(), g.lon_rad.to_degrees(), g.height_m)
    })
}

/// A protection level as text: `inf` when unbounded.
fn pl(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.2}")
    } else {
        "inf".into()
    }
}

fn create(path: &Path, what: &str) -> Result<std::io::BufWriter<std::fs::File>> {
    crate::replay::plot::check_folder(path, what)?;
    std::fs::File::create(path)
        .map(std::io::BufWriter::new)
        .map_err(|e| anyhow!("{what} {}: cannot create it: {e}", path.display()))
}

/// RTKLIB's solution format (`outsol`, LLH, GPST), then the integrity
/// columns: decision, HPL and VPL (m), the excluded satellites (`-` for
/// none). Quality flag 5 (single point). Epochs without a position (the
/// monitor refused them) have no line, as RTKLIB writes none.
pub fn write_pos(path: &Path, recs: &[EpochRecord], inputs: &[&Path]) -> Result<()> {
    let mut w = create(path, "--pos")?;
    let mut head = String::new();
    let _ = writeln!(
        head,
        "% program   : raim replay {}",
        env!("CARGO_PKG_VERSION")
    );
    for p in inputs {
        let _ = writeln!(head, "% inp file  : {}", p.display());
    }
    if let (Some(a), Some(b)) = (recs.first(), recs.last()) {
        let _ = writeln!(head, "% obs start : {} GPST", gpst_text(a.time_gps_s));
        let _ = writeln!(head, "% obs end   : {} GPST", gpst_text(b.time_gps_s));
    }
    let _ = writeln!(head, "% pos mode  : single");
    let _ = writeln!(
        head,
        "% integrity : decision (ok|excluded|unavailable|alarm), hpl(m), vpl(m) (inf: unbounded), excluded satellites; see docs/FORMATS.md"
    );
    let _ = writeln!(head, "%");
    let _ = writeln!(
        head,
        "%  GPST                  latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   sde(m)   sdu(m)  sdne(m)  sdeu(m)  sdun(m) age(s)  ratio  decision      hpl(m)     vpl(m) excluded"
    );
    w.write_all(head.as_bytes())?;
    for r in recs {
        let Some((lat, lon, h)) = llh(r) else {
            continue;
        };
        let s = r.sigma_enu_m;
        let sd = |v: f64| if v.is_finite() { v } else { 0.0 };
        let excl = if r.excluded_ids.is_empty() {
            "-".to_string()
        } else {
            r.excluded.join(",")
        };
        writeln!(
            w,
            "{} {:14.9} {:14.9} {:10.4} {:3} {:3} {:8.4} {:8.4} {:8.4} {:8.4} {:8.4} {:8.4} {:6.2} {:6.1}  {:<12} {:>9} {:>10} {}",
            gpst_text(r.time_gps_s),
            lat,
            lon,
            h,
            5,
            r.n_sats - r.excluded_ids.len(),
            sd(s[1]),
            sd(s[0]),
            sd(s[2]),
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            r.decision,
            pl(r.hpl_m),
            pl(r.vpl_m),
            excl,
        )?;
    }
    w.flush()?;
    Ok(())
}

/// One CSV row per epoch (lists joined with `;`, empty for none; `inf`
/// for an unbounded protection level).
pub fn write_csv(path: &Path, recs: &[EpochRecord]) -> Result<()> {
    let mut w = create(path, "--csv")?;
    writeln!(
        w,
        "time_gps_s,gpst,decision,alarm_cause,n_sats,initial_statistic,initial_threshold,initial_dof,final_statistic,final_threshold,final_dof,candidate,excluded,lat_deg,lon_deg,height_m,error_e_m,error_n_m,error_u_m,error_h_m,error_v_m,hpl_m,vpl_m,sigma_e_m,sigma_n_m,sigma_u_m,faulted,error"
    )?;
    let num = |v: f64| {
        if v.is_nan() {
            String::new()
        } else if v.is_infinite() {
            "inf".into()
        } else {
            format!("{v}")
        }
    };
    let opt = |v: Option<f64>| v.map_or(String::new(), num);
    for r in recs {
        let g = llh(r);
        let e = r.error_enu_m;
        let faulted: Vec<String> = r.faulted.iter().map(|(s, b)| format!("{s}{b:+}")).collect();
        let err = r
            .error
            .as_deref()
            .map(|e| format!("\"{}\"", e.replace('"', "\"\"")))
            .unwrap_or_default();
        writeln!(
            w,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            r.time_gps_s,
            gpst_text(r.time_gps_s),
            r.decision,
            r.alarm_cause.as_deref().unwrap_or(""),
            r.n_sats,
            num(r.initial_statistic),
            num(r.initial_threshold),
            r.initial_dof,
            num(r.final_statistic),
            num(r.final_threshold),
            r.final_dof,
            r.candidate.as_deref().unwrap_or(""),
            r.excluded.join(";"),
            opt(g.map(|g| g.0)),
            opt(g.map(|g| g.1)),
            opt(g.map(|g| g.2)),
            opt(e.map(|e| e[0])),
            opt(e.map(|e| e[1])),
            opt(e.map(|e| e[2])),
            opt(r.error_h_m),
            opt(r.error_v_m),
            num(r.hpl_m),
            num(r.vpl_m),
            num(r.sigma_enu_m[0]),
            num(r.sigma_enu_m[1]),
            num(r.sigma_enu_m[2]),
            faulted.join(";"),
            err,
        )?;
    }
    w.flush()?;
    Ok(())
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// KML colours (aabbggrr) of the decisions: green ok, orange excluded,
/// grey unavailable, red alarm.
const DECISIONS: [(&str, &str); 4] = [
    ("ok", "ff00c000"),
    ("excluded", "ff0080ff"),
    ("unavailable", "ff909090"),
    ("alarm", "ff0000ff"),
];

/// What a point's description says: decision, PLs, exclusions, faults.
fn describe(r: &EpochRecord) -> String {
    let mut d = format!(
        "{} GPST: {}; HPL {} m, VPL {} m",
        gpst_text(r.time_gps_s),
        r.decision,
        pl(r.hpl_m),
        pl(r.vpl_m)
    );
    if let Some(c) = &r.alarm_cause {
        let _ = write!(d, "; cause {c}");
    }
    if r.excluded.is_empty() {
        d.push_str("; excluded: none");
    } else {
        let _ = write!(d, "; excluded: {}", r.excluded.join(", "));
    }
    if !r.faulted.is_empty() {
        let f: Vec<String> = r
            .faulted
            .iter()
            .map(|(s, b)| format!("{s} {b:+.1} m"))
            .collect();
        let _ = write!(d, "; injected: {}", f.join(", "));
    }
    d
}

/// A KML document: a style per decision, the whole track as a line, and
/// one placemark per epoch with a position, coloured by its decision,
/// named by its time and describing the excluded satellites.
pub fn write_kml(path: &Path, recs: &[EpochRecord], title: &str) -> Result<()> {
    let mut w = create(path, "--kml")?;
    writeln!(w, r#"<?xml version="1.0" encoding="UTF-8"?>"#)?;
    writeln!(w, r#"<kml xmlns="http://www.opengis.net/kml/2.2">"#)?;
    writeln!(w, "<Document>")?;
    writeln!(w, "<name>{}</name>", xml_escape(title))?;
    writeln!(
        w,
        "<description>Colours: green ok, orange excluded, grey unavailable, red alarm (docs/FORMATS.md)</description>"
    )?;
    for (name, colour) in DECISIONS {
        writeln!(
            w,
            "<Style id=\"{name}\"><IconStyle><color>{colour}</color><scale>0.5</scale><Icon><href>http://maps.google.com/mapfiles/kml/shapes/shaded_dot.png</href></Icon></IconStyle></Style>"
        )?;
    }
    writeln!(
        w,
        "<Style id=\"track\"><LineStyle><color>ffffffff</color><width>1</width></LineStyle></Style>"
    )?;
    let points: Vec<(&EpochRecord, (f64, f64, f64))> =
        recs.iter().filter_map(|r| llh(r).map(|g| (r, g))).collect();
    writeln!(w, "<Placemark><name>track</name><styleUrl>#track</styleUrl><LineString><altitudeMode>absolute</altitudeMode><coordinates>")?;
    for (_, (lat, lon, h)) in &points {
        writeln!(w, "{lon:.9},{lat:.9},{h:.3}")?;
    }
    writeln!(w, "</coordinates></LineString></Placemark>")?;
    writeln!(w, "<Folder><name>epochs</name>")?;
    for (r, (lat, lon, h)) in &points {
        let style = if DECISIONS.iter().any(|(n, _)| *n == r.decision) {
            r.decision.as_str()
        } else {
            "alarm"
        };
        writeln!(
            w,
            "<Placemark><name>{}</name><TimeStamp><when>{}</when></TimeStamp><styleUrl>#{style}</styleUrl><description>{}</description><ExtendedData><Data name=\"decision\"><value>{}</value></Data><Data name=\"excluded\"><value>{}</value></Data></ExtendedData><Point><altitudeMode>absolute</altitudeMode><coordinates>{lon:.9},{lat:.9},{h:.3}</coordinates></Point></Placemark>",
            r.tod,
            utc_iso(r.time_gps_s),
            xml_escape(&describe(r)),
            r.decision,
            r.excluded.join(","),
        )?;
    }
    writeln!(w, "</Folder>")?;
    writeln!(w, "</Document>")?;
    writeln!(w, "</kml>")?;
    w.flush()?;
    Ok(())
}

/// A GPX 1.1 track; each point's `type` is its decision and its `desc`
/// the decision, PLs and excluded satellites.
pub fn write_gpx(path: &Path, recs: &[EpochRecord], title: &str) -> Result<()> {
    let mut w = create(path, "--gpx")?;
    writeln!(w, r#"<?xml version="1.0" encoding="UTF-8"?>"#)?;
    writeln!(
        w,
        r#"<gpx version="1.1" creator="raim replay" xmlns="http://www.topografix.com/GPX/1/1">"#
    )?;
    writeln!(w, "<trk><name>{}</name><trkseg>", xml_escape(title))?;
    for r in recs {
        let Some((lat, lon, h)) = llh(r) else {
            continue;
        };
        writeln!(
            w,
            "<trkpt lat=\"{lat:.9}\" lon=\"{lon:.9}\"><ele>{h:.3}</ele><time>{}</time><desc>{}</desc><type>{}</type></trkpt>",
            utc_iso(r.time_gps_s),
            xml_escape(&describe(r)),
            r.decision
        )?;
    }
    writeln!(w, "</trkseg></trk>")?;
    writeln!(w, "</gpx>")?;
    w.flush()?;
    Ok(())
}

/// The NMEA stream, one sentence a line, each ended CR LF as NMEA 0183
/// requires (the same bytes as `--nmea only`).
pub fn write_nmea<'a>(path: &Path, sentences: impl IntoIterator<Item = &'a String>) -> Result<()> {
    let mut w = create(path, "--nmea-file")?;
    for s in sentences {
        write!(w, "{}\r\n", s.trim_end())?;
    }
    w.flush()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The GPS origin and a known date: 0759's first epoch, 2005-04-02
    /// 00:00:00 GPST = GPS week 1316, second 518400.
    #[test]
    fn gps_time_prints_as_its_calendar_date() {
        assert_eq!(gpst_text(0.0), "1980/01/06 00:00:00.000");
        let t = 1316.0 * 604_800.0 + 518_400.0;
        assert_eq!(gpst_text(t), "2005/04/02 00:00:00.000");
        assert_eq!(gpst_text(t + 30.5), "2005/04/02 00:00:30.500");
        // 13 leap seconds in 2005: UTC is 13 s behind GPS time.
        assert_eq!(utc_iso(t), "2005-04-01T23:59:47Z");
    }
}
