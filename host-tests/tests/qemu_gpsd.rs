//! gpsd as a real NMEA client of the firmware: the NMEA the firmware writes
//! under QEMU is served to Debian's gpsd (`-b -n -N`: read-only, no wait
//! for a client, foreground), and gpsd's JSON must carry our numbers: TPV
//! `epx`/`epy`/`epv` equal GBS fields 3/2/4 (east, north, up 1-sigma
//! errors), and the GST report equals our GST sentence.
//!
//! Needs `gpsd` (scripts/test.sh installs it with qemu-system-arm).

mod qemu_common;

use std::io::{BufRead, BufReader, Write};
use std::net::{TcpListener, TcpStream};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use qemu_common::{range_vectors, session};
use raim_core::{Config, Epoch, Phase};

/// Our NMEA prints 3 decimals: agreement to half a unit of the last digit.
const NMEA_ROUNDING_M: f64 = 0.0005 + 1e-9;

fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

fn fields(sentence: &str) -> Vec<String> {
    let body = sentence.trim_start_matches('$').split('*').next().unwrap();
    body.split(',').map(str::to_string).collect()
}

struct Gpsd(std::process::Child);
impl Drop for Gpsd {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

#[test]
fn qemu_gpsd_reads_our_gbs_and_gst() {
    // The firmware's NMEA for the pseudorange epochs (1 s apart, 2024-02-29).
    let mut fw = session();
    fw.configure(&Config::preset(Phase::Terminal)).unwrap();
    let mut epochs: Vec<Vec<String>> = Vec::new();
    for _ in 0..2 {
        for (_, sats, apriori) in range_vectors(3).iter().take(4) {
            let t = 1_709_208_000.0 + epochs.len() as f64;
            let p = fw.process(&Epoch::ranges(t, sats, *apriori)).unwrap();
            assert!(p.outcome.is_ok(), "{:?}", p.outcome);
            epochs.push(p.nmea);
        }
    }
    drop(fw);

    // An NMEA source for gpsd on loopback, and gpsd itself.
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
        .set_read_timeout(Some(Duration::from_secs(20)))
        .unwrap();
    (&client)
        .write_all(b"?WATCH={\"enable\":true,\"json\":true}\n")
        .unwrap();
    let (mut feed, _) = source.accept().unwrap();
    let reports = std::thread::spawn(move || {
        let mut out = Vec::new();
        for line in BufReader::new(client).lines() {
            let Ok(line) = line else { break };
            let v: serde_json::Value = serde_json::from_str(&line).unwrap();
            let done = v["class"] == "GST"
                && out
                    .iter()
                    .filter(|r: &&serde_json::Value| r["class"] == "GST")
                    .count()
                    >= 7;
            out.push(v);
            if done {
                break;
            }
        }
        out
    });
    for e in &epochs {
        for s in e {
            feed.write_all(format!("{s}\r\n").as_bytes()).unwrap();
        }
        std::thread::sleep(Duration::from_millis(300));
    }
    std::thread::sleep(Duration::from_millis(500));
    drop(feed);
    let reports = reports.join().unwrap();

    // Match gpsd's reports to our epochs by time of day (hhmmss.ss).
    let mut tpv_checked = 0;
    let mut gst_checked = 0;
    for e in &epochs {
        let kind = |k: &str| fields(e.iter().find(|s| &s[3..6] == k).unwrap());
        let (gst, gbs) = (kind("GST"), kind("GBS"));
        let hhmmss = &gbs[1];
        let iso = format!("T{}:{}:{}", &hhmmss[0..2], &hhmmss[2..4], &hhmmss[4..6]);
        let num = |s: &str| s.parse::<f64>().unwrap();
        for r in reports
            .iter()
            .filter(|r| r["time"].as_str().is_some_and(|t| t.contains(&iso)))
        {
            let close = |key: &str, want: f64| {
                let got = r[key]
                    .as_f64()
                    .unwrap_or_else(|| panic!("{key} missing in {r}"));
                assert!(
                    (got - want).abs() <= NMEA_ROUNDING_M,
                    "{key}: gpsd {got}, ours {want} ({r})"
                );
            };
            if r["class"] == "TPV" && r.get("epx").is_some() {
                close("epx", num(&gbs[3]));
                close("epy", num(&gbs[2]));
                close("epv", num(&gbs[4]));
                tpv_checked += 1;
            }
            if r["class"] == "GST" {
                close("rms", num(&gst[2]));
                close("major", num(&gst[3]));
                close("minor", num(&gst[4]));
                close("lat", num(&gst[6]));
                close("lon", num(&gst[7]));
                close("alt", num(&gst[8]));
                gst_checked += 1;
            }
        }
    }
    eprintln!(
        "checked {tpv_checked} TPV, {gst_checked} GST; e.g. {:?}",
        reports.iter().filter(|r| r["class"] == "TPV").nth(3)
    );
    assert!(
        tpv_checked >= 4 && gst_checked >= 4,
        "{tpv_checked} TPV, {gst_checked} GST checked of {} reports: {reports:?}",
        reports.len()
    );
}
