//! NMEA 0183 4.11 on a real epoch stream: GSI station 0759 (../shared/data)
//! through the host's monitor and NMEA writer (the firmware's, with this
//! build's geoid and sky sentences). Every sentence parses with pynmea2,
//! and with the `nmea` crate but for GBS, which that crate cannot read in
//! the standard's form (test comment); GGA's altitude is above mean sea level, within
//! 1 m of RTKLIB's 34.041 m (geoid separation 36.478 m) at 00:00:00; and
//! gpsd reports SKY with the satellites seen (elevation, azimuth) and the
//! DOPs of the geometry, and a TPV altMSL equal to GGA's. (gpsd 3.22 marks
//! a GSV satellite used only with a C/N0 above zero, and 0759's RINEX has
//! no signal strengths: its `uSat` stays 0, docs/PROTOCOL.md.)
//!
//! NMEA 4.11 satellite numbering on ESBC (G+E+C): every GSA, GSV and GBS
//! number read within its system ID or talker is the satellite it stands
//! for, and gpsd's SKY is its reading of them (`gpsd_reading`).
//!
//!     cargo test --release -p host-tests --test nmea_0759 -- --nocapture
//!
//! Needs `gpsd` and pynmea2 (scripts/install-deps.sh test).

mod replay_common;

use std::io::{BufRead, BufReader, Write};
use std::net::{TcpListener, TcpStream};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use raim_core::{Epoch, Raim, SatId, System};
use raim_gnss::ranging::{prepare_epoch, RangingOptions};
use raim_gnss::{NavData, ObsData};
use raim_proto::nmea::{epoch_sentences, Sky, BUILT};
use raim_proto::WireResult;
use replay_common::{data, geodetic_config};

/// RTKLIB 2.4.3's single-point MSL height at 0759, 2005-04-02 00:00:00.
const RTKLIB_MSL_M: f64 = 34.041;
/// Agreement asked of our MSL altitude at the same epoch.
const MSL_TOLERANCE_M: f64 = 1.0;
/// Our NMEA DOPs have 2 decimals.
const DOP_ROUNDING: f64 = 0.005 + 1e-9;

/// The first `n` epochs of 0759 as NMEA sentences (without CRLF).
fn sentences(n: usize) -> Vec<Vec<String>> {
    let obs = ObsData::load(&data("07590920.05o")).unwrap();
    let nav = NavData::load(&data("07590920.05n")).unwrap();
    let opts = RangingOptions {
        systems: vec![System::Gps],
        elevation_mask_rad: 15f64.to_radians(),
        ..Default::default()
    };
    let cfg = geodetic_config();
    let mut raim = Raim::<48>::new();
    obs.epochs
        .iter()
        .take(n)
        .map(|e| {
            let p = prepare_epoch(&nav, e, &opts, obs.approx_position_m);
            let sats = p.observations();
            let epoch = Epoch::ranges(e.time_gps_s, &sats, p.reference_m);
            let w = WireResult::from_result(&raim.process(&cfg, &epoch).unwrap());
            epoch_sentences(&w, &Sky::new(&epoch), BUILT)
                .unwrap()
                .iter()
                .map(|s| s.trim_end().to_string())
                .collect()
        })
        .collect()
}

fn fields(sentence: &str) -> Vec<String> {
    let body = sentence.trim_start_matches('$').split('*').next().unwrap();
    body.split(',').map(str::to_string).collect()
}

fn find(epoch: &[String], kind: &str) -> Vec<String> {
    fields(epoch.iter().find(|s| &s[3..6] == kind).unwrap())
}

/// Verifies: NMEA-ALT
#[test]
fn msl_altitude_at_0759_is_rtklibs() {
    let epochs = sentences(1);
    let gga = find(&epochs[0], "GGA");
    let (alt, sep): (f64, f64) = (gga[9].parse().unwrap(), gga[11].parse().unwrap());
    eprintln!("0759 00:00:00 GGA: altitude {alt} m MSL, separation {sep} m");
    assert!(
        (alt - RTKLIB_MSL_M).abs() <= MSL_TOLERANCE_M,
        "altitude {alt} m against RTKLIB's {RTKLIB_MSL_M} m"
    );
}

/// Verifies: NMEA-FORMAT
#[test]
fn every_sentence_parses_with_the_nmea_crate_and_pynmea2() {
    parse_everywhere(&sentences(40));
}

/// Every sentence of `epochs` parses with the `nmea` crate (GBS: framing
/// only) and with pynmea2, and every kind is there.
fn parse_everywhere(epochs: &[Vec<String>]) {
    let all: Vec<&String> = epochs.iter().flatten().collect();
    let mut kinds = std::collections::BTreeSet::new();
    for s in &all {
        if &s[3..6] == "GBS" {
            // The nmea crate 0.8 reads GBS fields 2-3 (the latitude and
            // longitude errors, m) as a position with hemisphere letters,
            // so no GBS of the standard's form parses whole there (its own
            // log test skips GBS). Its framing and checksum must pass, and
            // the full parse must fail only there, in the error fields.
            nmea::parse_nmea_sentence(s).unwrap_or_else(|e| panic!("nmea crate: {e:?} on {s}"));
            let err = format!("{:?}", nmea::parse_str(s).unwrap_err());
            let errors = fields(s)[2..].join(",");
            assert!(err.contains(&errors), "{err} on {s}");
        } else {
            nmea::parse_str(s).unwrap_or_else(|e| panic!("nmea crate: {e:?} on {s}"));
        }
        kinds.insert(s[3..6].to_string());
    }
    assert_eq!(
        kinds.into_iter().collect::<Vec<_>>(),
        ["GBS", "GGA", "GSA", "GST", "GSV", "RMC", "VTG", "ZDA"]
    );
    let script = "import sys, pynmea2\n\
n = 0\n\
for line in sys.stdin:\n    pynmea2.parse(line.strip(), check=True); n += 1\n\
print(n)\n";
    let mut py = Command::new("python3")
        .args(["-c", script])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("python3");
    let text: String = all.iter().map(|s| format!("{s}\r\n")).collect();
    py.stdin.take().unwrap().write_all(text.as_bytes()).unwrap();
    let out = py.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "pynmea2: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        String::from_utf8_lossy(&out.stdout).trim(),
        all.len().to_string()
    );
}

struct Gpsd(std::process::Child);
impl Drop for Gpsd {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// gpsd 3.22's JSON reports for `epochs` fed over TCP, 300 ms apart.
fn gpsd_reports(epochs: &[Vec<String>]) -> Vec<serde_json::Value> {
    let source = TcpListener::bind("127.0.0.1:0").unwrap();
    let src_port = source.local_addr().unwrap().port();
    let gpsd_port = free_port();
    // gpsd's control socket, in a directory removed when the test ends.
    let dir = tempfile::Builder::new()
        .prefix("raim-gpsd-")
        .tempdir()
        .unwrap();
    let _gpsd = Gpsd(
        Command::new(if std::path::Path::new("/usr/sbin/gpsd").exists() {
            "/usr/sbin/gpsd"
        } else {
            "gpsd"
        })
        .args(["-b", "-n", "-N", "-S", &gpsd_port.to_string()])
        .arg("-F")
        .arg(dir.path().join("control.sock"))
        .arg(format!("tcp://127.0.0.1:{src_port}"))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("gpsd (apt-get install gpsd)"),
    );
    let deadline = Instant::now() + Duration::from_secs(10);
    let client = loop {
        match TcpStream::connect(("127.0.0.1", gpsd_port)) {
            Ok(c) => break c,
            Err(e) if Instant::now() > deadline => panic!("gpsd does not listen: {e}"),
            Err(_) => std::thread::sleep(Duration::from_millis(50)),
        }
    };
    client
        .set_read_timeout(Some(Duration::from_secs(5)))
        .unwrap();
    (&client)
        .write_all(b"?WATCH={\"enable\":true,\"json\":true}\n")
        .unwrap();
    let (mut feed, _) = source.accept().unwrap();
    let reports = std::thread::spawn(move || {
        let mut out = Vec::new();
        for line in BufReader::new(client).lines() {
            let Ok(line) = line else { break };
            out.push(serde_json::from_str::<serde_json::Value>(&line).unwrap());
        }
        out
    });
    for e in epochs {
        for s in e {
            feed.write_all(format!("{s}\r\n").as_bytes()).unwrap();
        }
        std::thread::sleep(Duration::from_millis(300));
    }
    std::thread::sleep(Duration::from_millis(500));
    drop(feed);
    reports.join().unwrap()
}

/// Verifies: NMEA-FORMAT, NMEA-ALT
#[test]
fn gpsd_reports_sky_dops_and_msl_altitude() {
    let epochs = sentences(8);
    let reports = gpsd_reports(&epochs);

    let sky: Vec<&serde_json::Value> = reports.iter().filter(|r| r["class"] == "SKY").collect();
    let tpv: Vec<&serde_json::Value> = reports
        .iter()
        .filter(|r| r["class"] == "TPV" && r.get("altMSL").is_some())
        .collect();
    eprintln!("e.g. {:?}\n{:?}", sky.last(), tpv.last());
    assert!(!sky.is_empty(), "no SKY in {reports:?}");
    // Seen: the GSV satellites of some epoch; used: its GSA's.
    let seen_counts: Vec<usize> = epochs
        .iter()
        .map(|e| find(e, "GSV")[3].parse().unwrap())
        .collect();
    let mut dops_checked = 0;
    for r in &sky {
        let sats = r["satellites"].as_array().expect("SKY satellites");
        assert!(seen_counts.contains(&sats.len()), "{r}");
        // DOPs equal to some epoch's GSA (gpsd reports the last ones).
        if let (Some(h), Some(p), Some(v)) =
            (r["hdop"].as_f64(), r["pdop"].as_f64(), r["vdop"].as_f64())
        {
            let matches = epochs.iter().any(|e| {
                let g = find(e, "GSA");
                let n = |k: usize| g[k].parse::<f64>().unwrap();
                (n(15) - p).abs() <= DOP_ROUNDING
                    && (n(16) - h).abs() <= DOP_ROUNDING
                    && (n(17) - v).abs() <= DOP_ROUNDING
            });
            assert!(matches, "SKY DOPs {p} {h} {v} are no epoch's GSA");
            dops_checked += 1;
        }
    }
    assert!(dops_checked > 0, "no DOPs in {sky:?}");
    // altMSL: GGA's altitude of one of the epochs.
    assert!(!tpv.is_empty(), "no TPV altMSL in {reports:?}");
    for r in &tpv {
        let got = r["altMSL"].as_f64().unwrap();
        assert!(
            epochs
                .iter()
                .any(|e| (find(e, "GGA")[9].parse::<f64>().unwrap() - got).abs() <= 0.0005 + 1e-9),
            "altMSL {got}"
        );
    }
}

/// One epoch of ESBC's G+E+C sky as NMEA, with the satellites in view and
/// used (in the writer's order).
struct SkyEpoch {
    nmea: Vec<String>,
    seen: Vec<SatId>,
    used: Vec<SatId>,
}

/// GPS - UTC at ESBC's date (2020-06-25), s.
const ESBC_LEAP_S: f64 = 18.0;
/// GPS time zero (1980-01-06) in Unix seconds.
const GPS_EPOCH_UNIX_S: f64 = 315_964_800.0;

/// The first `n` epochs of ESBC (G+E+C, ../shared/data) through the host's
/// monitor and NMEA writer.
fn esbc(n: usize) -> Vec<SkyEpoch> {
    let obs = ObsData::load(&data("ESBC00DNK_R_20201770000_03H_30S_MO.rnx.gz")).unwrap();
    let nav = NavData::load(&data("ESBC00DNK_R_20201770000_01D_MN.rnx.gz")).unwrap();
    let opts = RangingOptions::default();
    let cfg = geodetic_config();
    let mut raim = Raim::<48>::new();
    obs.epochs
        .iter()
        .take(n)
        .map(|e| {
            let p = prepare_epoch(&nav, e, &opts, obs.approx_position_m);
            let sats = p.observations();
            let t_utc_s = e.time_gps_s + GPS_EPOCH_UNIX_S - ESBC_LEAP_S;
            let epoch = Epoch::ranges(t_utc_s, &sats, p.reference_m);
            let w = WireResult::from_result(&raim.process(&cfg, &epoch).unwrap());
            // Each satellite's C/N0, from the RINEX S observables (gpsd
            // 3.22 marks a GSV satellite used only when its C/N0 is above
            // zero).
            let cn0: Vec<u8> = p.sats.iter().map(|s| s.cn0_dbhz).collect();
            assert!(cn0.iter().all(|&c| c > 0), "{cn0:?}");
            let sky = Sky {
                epoch: &epoch,
                cn0_dbhz: &cn0,
                velocity: None,
            };
            SkyEpoch {
                nmea: epoch_sentences(&w, &sky, BUILT)
                    .unwrap()
                    .iter()
                    .map(|s| s.trim_end().to_string())
                    .collect(),
                seen: sats.iter().map(|s| s.id).collect(),
                used: w
                    .satellites
                    .iter()
                    .filter(|s| s.used)
                    .map(|s| s.id)
                    .collect(),
            }
        })
        .collect()
}

/// The system of an NMEA 4.11 system ID (GSA field 18, GBS field 9).
fn system_of_id(id: &str) -> System {
    match id {
        "1" => System::Gps,
        "2" => System::Glonass,
        "3" => System::Galileo,
        "4" => System::Beidou,
        "5" => System::Qzss,
        _ => panic!("system ID {id}"),
    }
}

/// The system of a GSV talker.
fn system_of_talker(talker: &str) -> System {
    match talker {
        "GP" => System::Gps,
        "GL" => System::Glonass,
        "GA" => System::Galileo,
        "GB" => System::Beidou,
        "GQ" => System::Qzss,
        _ => panic!("GSV talker {talker}"),
    }
}

/// An NMEA 4.11 satellite number read within its system: GPS 1-32,
/// GLONASS 65-96, Galileo 1-36, BeiDou 1-63, QZSS 1-10.
fn sat_of(sys: System, number: &str) -> SatId {
    let n: u8 = number.parse().unwrap();
    let (lo, hi, offset) = match sys {
        System::Gps => (1, 32, 0),
        System::Glonass => (65, 96, 64),
        System::Galileo => (1, 36, 0),
        System::Beidou => (1, 63, 0),
        System::Qzss => (1, 10, 0),
    };
    assert!((lo..=hi).contains(&n), "{sys:?} number {n}");
    SatId::new(sys, n - offset)
}

/// NMEA 4.11 numbering on a G+E+C stream: each GSA's numbers, read within
/// its system ID, are the used satellites of that system; each GSV set's,
/// read within its talker, the satellites in view; GBS's satellite is one
/// in view. pynmea2 and the `nmea` crate parse every sentence, and gpsd's
/// SKY reports are its reading of them ([`gpsd_reading`]: right from
/// gpsd 3.25 on; Debian 12's 3.22 places a GSV's later-part numbers above
/// 32 in SBAS and reads no GSA system ID).
///
/// Verifies: NMEA-NUMBERING, NMEA-FORMAT
#[test]
fn esbc_numbers_satellites_within_their_system_and_gpsd_reads_them() {
    let epochs = esbc(6);
    let nmea: Vec<Vec<String>> = epochs.iter().map(|e| e.nmea.clone()).collect();
    parse_everywhere(&nmea);
    for e in &epochs {
        let systems: std::collections::BTreeSet<System> = e.seen.iter().map(|s| s.system).collect();
        assert_eq!(
            systems.into_iter().collect::<Vec<_>>(),
            [System::Gps, System::Galileo, System::Beidou]
        );
        let (mut used, mut seen) = (Vec::new(), Vec::new());
        for s in &e.nmea {
            let f = fields(s);
            match &f[0][2..] {
                "GSA" => {
                    assert_eq!(&f[0][..2], "GN", "{s}");
                    let sys = system_of_id(&f[18]);
                    used.extend(
                        f[3..15]
                            .iter()
                            .filter(|n| !n.is_empty())
                            .map(|n| sat_of(sys, n)),
                    );
                }
                "GSV" => {
                    let sys = system_of_talker(&f[0][..2]);
                    seen.extend(f[4..f.len() - 1].chunks(4).map(|c| sat_of(sys, &c[0])));
                }
                "GBS" if !f[5].is_empty() => {
                    let id = sat_of(system_of_id(&f[9]), &f[5]);
                    assert!(e.seen.contains(&id), "{s}");
                }
                _ => {}
            }
        }
        assert_eq!(used, e.used, "{:?}", e.nmea);
        assert_eq!(seen, e.seen, "{:?}", e.nmea);
    }

    let strict = gpsd_reads_system_ids();
    let want: Vec<Vec<Reading>> = nmea.iter().map(|e| gpsd_reading(e, strict)).collect();
    let reports = gpsd_reports(&nmea);
    let skies: Vec<Vec<Reading>> = reports
        .iter()
        .filter(|r| r["class"] == "SKY" && r.get("satellites").is_some())
        .map(|r| {
            let mut got: Vec<Reading> = r["satellites"]
                .as_array()
                .unwrap()
                .iter()
                .map(|s| {
                    let n = |k: &str| s[k].as_f64().unwrap_or_else(|| panic!("{k} in {s}"));
                    Reading {
                        gnssid: n("gnssid") as u16,
                        svid: n("svid") as u16,
                        prn: n("PRN") as u16,
                        el_deg: n("el") as u16,
                        az_deg: n("az") as u16,
                        used: s["used"] == true,
                    }
                })
                .collect();
            got.sort();
            got
        })
        .collect();
    assert!(!skies.is_empty(), "no SKY in {reports:?}");
    // gpsd reports a SKY as each GSV set ends: one epoch's first systems,
    // then all of them.
    for got in &skies {
        assert!(
            want.iter().any(|w| got.iter().all(|s| w.contains(s))),
            "gpsd's sky {got:?} is in no epoch's reading {want:?}"
        );
    }
    let whole = want.iter().filter(|w| skies.contains(w)).count();
    assert!(whole > 0, "no SKY with a whole epoch's sky: {skies:?}");
    let used: usize = skies
        .iter()
        .map(|s| s.iter().filter(|r| r.used).count())
        .sum();
    assert!(used > 0, "no satellite used in {skies:?}");
    eprintln!(
        "gpsd (reads system IDs: {strict}): {} SKY reports, {whole} with a whole epoch; e.g. {:?}",
        skies.len(),
        skies.last()
    );
}

/// One satellite as gpsd's SKY report gives it.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
struct Reading {
    gnssid: u16,
    svid: u16,
    prn: u16,
    el_deg: u16,
    az_deg: u16,
    used: bool,
}

/// Whether the installed gpsd reads NMEA 4.11's numbers by the system ID
/// in every sentence (3.25 and later: GSA field 18 and the talker of every
/// GSV part), or as 3.22 does (below).
fn gpsd_reads_system_ids() -> bool {
    let out = Command::new(if std::path::Path::new("/usr/sbin/gpsd").exists() {
        "/usr/sbin/gpsd"
    } else {
        "gpsd"
    })
    .arg("-V")
    .output()
    .expect("gpsd -V");
    let text =
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    let version: Vec<u32> = text
        .split_whitespace()
        .nth(1)
        .unwrap_or_else(|| panic!("gpsd -V: {text}"))
        .split('.')
        .map(|v| v.parse().unwrap_or(0))
        .collect();
    version.as_slice() >= [3, 25].as_slice()
}

/// What gpsd makes of one epoch's sentences, from its
/// drivers/driver_nmea0183.c. Read right (`strict`, gpsd 3.25 and later):
/// u-blox gnssid and svid, and gpsd's extended PRN (GPS 1-32, Galileo
/// 301-336, BeiDou 401-463, QZSS 193-202, GLONASS 65-96), used when in a
/// GSA of its system. gpsd 3.22 takes the system from the talker of a
/// GSV's first part only, so a later part's numbers above 32 fall into
/// its SBAS range (svid + 87), and reads no GSA system ID, so a GNGSA
/// number is a GPS (or SBAS) PRN: a satellite is marked used when that PRN
/// is among the GSA numbers (and its C/N0 is above zero).
fn gpsd_reading(epoch: &[String], strict: bool) -> Vec<Reading> {
    let mut used_numbers = Vec::new();
    let mut used_sats = Vec::new();
    for s in epoch.iter().filter(|s| &s[3..6] == "GSA") {
        let f = fields(s);
        let sys = system_of_id(&f[18]);
        for n in f[3..15].iter().filter(|n| !n.is_empty()) {
            used_numbers.push(n.parse::<u16>().unwrap());
            used_sats.push(sat_of(sys, n));
        }
    }
    let mut out = Vec::new();
    for s in epoch.iter().filter(|s| &s[3..6] == "GSV") {
        let f = fields(s);
        let sys = system_of_talker(&f[0][..2]);
        let first_part = f[2] == "1";
        for c in f[4..f.len() - 1].chunks(4) {
            let n: u16 = c[0].parse().unwrap();
            let id = sat_of(sys, &c[0]);
            let prn = u16::from(id.prn);
            let (gnssid, svid, ext) = match sys {
                System::Gps => (0, prn, prn),
                System::Galileo => (2, prn, 300 + prn),
                System::Beidou => (3, prn, 400 + prn),
                System::Qzss => (5, prn, 192 + prn),
                System::Glonass => (6, prn, 64 + prn),
            };
            let (gnssid, svid, ext) = if strict || first_part || !(33..=64).contains(&n) {
                (gnssid, svid, ext)
            } else {
                (1, n + 87, n)
            };
            let used = if strict {
                used_sats.contains(&id)
            } else {
                used_numbers.contains(&ext)
            };
            out.push(Reading {
                gnssid,
                svid,
                prn: ext,
                el_deg: c[1].parse().unwrap(),
                az_deg: c[2].parse().unwrap(),
                used,
            });
        }
    }
    out.sort();
    out
}
