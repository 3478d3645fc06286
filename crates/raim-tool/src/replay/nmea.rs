//! NMEA 0183 output (SPEC §11): GGA (fix), GSA-free minimal set plus GBS
//! (the RAIM sentence: expected errors, the most likely failed satellite,
//! its bias estimate and standard deviation).

use super::record::EpochRecord;

/// XOR checksum of the characters between '$' and '*'.
pub fn checksum(body: &str) -> u8 {
    body.bytes().fold(0u8, |a, b| a ^ b)
}

fn sentence(body: String) -> String {
    format!("${body}*{:02X}", checksum(&body))
}

fn lat_lon(lat_rad: f64, lon_rad: f64) -> String {
    let (lat, lon) = (lat_rad.to_degrees(), lon_rad.to_degrees());
    let dm = |v: f64, w: usize| {
        let a = v.abs();
        let d = a.floor();
        format!("{:0w$}{:07.4}", d as u32, (a - d) * 60.0, w = w)
    };
    format!(
        "{},{},{},{}",
        dm(lat, 2),
        if lat >= 0.0 { 'N' } else { 'S' },
        dm(lon, 3),
        if lon >= 0.0 { 'E' } else { 'W' }
    )
}

/// GGA and GBS for one epoch; `utc` is hhmmss.ss.
pub fn sentences(r: &EpochRecord, utc: &str) -> Vec<String> {
    let mut out = Vec::new();
    let usable = r.usable();
    // Satellites in the solution; the altitude field carries the
    // ellipsoidal height (geoid separation given as 0).
    let used = r.n_sats.saturating_sub(r.excluded_ids.len());
    let pos = match r.geodetic {
        Some((lat, lon, h)) if usable => {
            format!("{},1,{:02},,{:.3},M,0.0,M,,", lat_lon(lat, lon), used, h)
        }
        _ => format!(",,,,0,{used:02},,,M,,M,,"),
    };
    out.push(sentence(format!("GNGGA,{utc},{pos}")));
    let [se, sn, su] = r.sigma_enu_m;
    let (id, bias, sd) = match r.gbs_bias {
        Some((id, b, sd)) => (id.prn.to_string(), format!("{b:.1}"), format!("{sd:.1}")),
        None => (String::new(), String::new(), String::new()),
    };
    let f = |v: f64| {
        if v.is_finite() {
            format!("{v:.1}")
        } else {
            String::new()
        }
    };
    out.push(sentence(format!(
        "GNGBS,{utc},{},{},{},{id},,{bias},{sd}",
        f(sn),
        f(se),
        f(su)
    )));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The checksum of a published sentence: "$GPGGA,123519,4807.038,N,
    /// 01131.000,E,1,08,0.9,545.4,M,46.9,M,,*47" (the NMEA reference example).
    #[test]
    fn checksum_of_the_reference_gga() {
        let body = "GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,";
        assert_eq!(checksum(body), 0x47);
    }

    #[test]
    fn latitude_longitude_format() {
        let s = lat_lon(48.1173f64.to_radians(), (-11.5166667f64).to_radians());
        assert_eq!(s, "4807.0380,N,01131.0000,W");
    }
}
