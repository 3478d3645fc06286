//! The two real receiver logs of ../shared/data, decoded: what each holds
//! (counts from the data README), and a cut last frame ends them cleanly.

use std::path::{Path, PathBuf};

use raim_core::System;
use raim_recv::{read_all, Format};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data")
        .join(name)
}

#[test]
fn gmsd7_rtcm3() {
    let p = data("GMSD7_20121014.rtcm3");
    let r = read_all(Format::Rtcm3, std::fs::File::open(&p).unwrap(), p.clone()).unwrap();
    eprintln!("{}", r.counts);
    let c = &r.counts;
    assert_eq!(c.bytes, 262_144);
    assert_eq!(r.obs.epochs.len(), 257);
    // 15 GPS ephemerides (1019) and 16 GLONASS (1020).
    let gps: usize = r
        .nav
        .ephemerides
        .iter()
        .filter(|(id, _)| id.system == System::Gps)
        .map(|(_, v)| v.len())
        .sum();
    assert_eq!(gps, 15);
    let glo: usize = r.nav.glonass.values().map(Vec::len).sum();
    assert!(glo > 0 && glo <= 16, "{glo}");
    assert_eq!(c.bad_checksum, 0);
    assert_eq!(c.garbage_bytes, 0);
    // The last frame is cut by the 256 KiB limit.
    assert!(c.truncated_tail_bytes > 0 && c.truncated_tail_bytes < 1029);
    // 1 Hz across the GPS week boundary (week 1709 to 1710).
    let t: Vec<f64> = r.obs.epochs.iter().map(|e| e.time_gps_s).collect();
    assert!(
        t.windows(2).all(|w| (w[1] - w[0] - 1.0).abs() < 1e-6),
        "{:?}",
        &t[..3]
    );
    assert!((t[0] - (1709.0 * 604_800.0 + 604_784.0)).abs() < 1e-6);
    let first = &r.obs.epochs[0];
    let g1 = &first.sats[&raim_core::SatId::new(System::Gps, 1)];
    let codes: Vec<&str> = g1.iter().map(|c| c.code.as_str()).collect();
    assert!(
        codes.contains(&"C1C") && codes.contains(&"C2W"),
        "{codes:?}"
    );
    eprintln!(
        "G1 codes {codes:?}; systems {:?}",
        first.sats.keys().map(|k| k.to_string()).collect::<Vec<_>>()
    );
}

#[test]
fn lea4t_ubx() {
    let p = data("ubx_20080526.ubx");
    let r = read_all(Format::Ubx, std::fs::File::open(&p).unwrap(), p.clone()).unwrap();
    eprintln!("{}", r.counts);
    let c = &r.counts;
    assert_eq!(r.obs.epochs.len(), 242);
    assert_eq!(c.bad_checksum, 0);
    // Subframe 4 page 18 (12.5 min cycle) is not in these 4 minutes.
    assert!(r.nav.klobuchar.is_none());
    assert_eq!(c.garbage_bytes, 0);
    let n: usize = r.nav.ephemerides.values().map(Vec::len).sum();
    eprintln!(
        "{n} ephemerides for {:?}",
        r.nav
            .ephemerides
            .keys()
            .map(|k| k.to_string())
            .collect::<Vec<_>>()
    );
    assert!(n >= 8);
}
