//! An `Unavailable` or `Alarm` epoch is never a fix for an NMEA
//! client. The firmware's NMEA under QEMU is served to Debian's gpsd; for
//! the epochs the monitor did not clear, gpsd must report no fix (TPV mode
//! <= 1), while the cleared epochs around them are 3D fixes (mode 3).
//!
//! Needs `gpsd` (scripts/test.sh installs it with qemu-system-arm).

mod qemu_common;

use std::io::{BufRead, BufReader, Write};
use std::net::{TcpListener, TcpStream};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use qemu_common::{host_result, range_epoch, session, Rng};
use raim_core::{AlertLimits, Config, Decision, Epoch, Phase, System};

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

/// Serve `epochs` (NMEA sentences per epoch) to gpsd; its JSON reports, up
/// to the TPV of the last of `n_epochs` epochs (or gpsd's silence).
fn through_gpsd(epochs: &[Vec<String>], n_epochs: usize) -> Vec<serde_json::Value> {
    let source = TcpListener::bind("127.0.0.1:0").unwrap();
    let src_port = source.local_addr().unwrap().port();
    let gpsd_port = free_port();
    // gpsd's control socket, in a directory removed when the test ends.
    let dir = tempfile::Builder::new()
        .prefix("raim-gpsd-int-")
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
    // Epoch k is stamped 12:00:0k (see the test).
    let last_tag = format!("T12:00:{:02}", n_epochs.saturating_sub(1));
    let reports = std::thread::spawn(move || {
        let mut out: Vec<serde_json::Value> = Vec::new();
        for line in BufReader::new(client).lines() {
            let Ok(line) = line else { break };
            let v: serde_json::Value = serde_json::from_str(&line).unwrap();
            // gpsd may report an epoch more than once (three TPVs for the
            // first epoch were seen), so a count of TPVs is no end mark: stop
            // at the last epoch's TPV (its time tag), else at the read
            // timeout or when gpsd closes.
            let last =
                v["class"] == "TPV" && v["time"].as_str().is_some_and(|t| t.contains(&last_tag));
            out.push(v);
            if last {
                break;
            }
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

#[test]
fn qemu_gpsd_reports_no_fix_for_unavailable_and_alarm_epochs() {
    let terminal = Config::preset(Phase::Terminal);
    // The smallest HAL the bounds allow, for an epoch whose HPL exceeds it.
    let tight = Config {
        alert: AlertLimits {
            hal_m: 40.0,
            val_m: None,
        },
        ..terminal
    };
    let sky: Vec<(f64, f64)> = (0..12)
        .map(|i| (i as f64 * 31.0, 12.0 + (i as f64 * 23.0) % 70.0))
        .collect();
    let mut rng = Rng::new(11);
    let clean = range_epoch(&sky[..10], &[System::Gps], &mut rng, &[]);
    // Five satellites, one redundant: a 300 m step is detected and cannot
    // be excluded (Alarm).
    let alarm = range_epoch(&sky[..5], &[System::Gps], &mut rng, &[(1, 300.0)]);
    let weak = range_epoch(&sky[..6], &[System::Gps], &mut rng, &[]);
    // (configuration, satellites, decision the host core gives)
    let plan = [
        (&terminal, &clean, Decision::Ok),
        (&terminal, &clean, Decision::Ok),
        (&tight, &weak, Decision::Unavailable),
        (&terminal, &clean, Decision::Ok),
        (&terminal, &alarm, Decision::Alarm),
        (&terminal, &clean, Decision::Ok),
        (&tight, &weak, Decision::Unavailable),
        (&terminal, &clean, Decision::Ok),
    ];
    let t0 = 1_709_208_000.0;
    let mut fw = session();
    let mut epochs = Vec::new();
    for (k, (cfg, sats, want)) in plan.iter().enumerate() {
        let epoch = Epoch::ranges(t0 + k as f64, sats, None);
        let host = host_result(cfg, &epoch).unwrap();
        assert_eq!(host.decision, *want, "epoch {k} on the host");
        fw.configure(cfg).unwrap();
        let p = fw.process(&epoch).unwrap();
        assert_eq!(p.outcome.as_ref().unwrap().decision, *want, "epoch {k}");
        epochs.push(p.nmea);
    }
    drop(fw);
    let reports = through_gpsd(&epochs, plan.len());
    let mut seen = [None; 8];
    for r in reports.iter().filter(|r| r["class"] == "TPV") {
        let Some(t) = r["time"].as_str() else {
            continue;
        };
        for (k, slot) in seen.iter_mut().enumerate() {
            // 2024-02-29T12:00:0k
            if t.contains(&format!("T12:00:{k:02}")) {
                let mode = r["mode"].as_i64().unwrap_or(0);
                *slot = Some(slot.map_or(mode, |m: i64| m.max(mode)));
            }
        }
    }
    eprintln!("gpsd TPV modes by epoch: {seen:?}");
    for (k, (_, _, want)) in plan.iter().enumerate() {
        match want {
            // gpsd reports from the second cycle on (it learns the cycle's
            // first sentence on the first).
            Decision::Ok if k == 0 => {}
            Decision::Ok => assert_eq!(seen[k], Some(3), "epoch {k}: {reports:?}"),
            _ => assert!(
                seen[k].is_none_or(|m| m <= 1),
                "epoch {k} reported as a fix: {seen:?}"
            ),
        }
    }
    // Not vacuous: gpsd reported the epochs around the bad ones as fixes.
    assert!(seen.iter().filter(|m| **m == Some(3)).count() >= 4);
}
