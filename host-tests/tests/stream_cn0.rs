//! C/N0 in GSV from a receiver's stream (issue 34, "NMEA"): the MSM's CNR
//! (DF403 in MSM4/5, DF408 in MSM6/7) of the signal each satellite is
//! ranged with (the pair's first), through the device's stream receiver
//! and raim-server's `Server` into the unit's GSV sentences, checked
//! against the RINEX S observables the ESBC stream was made from
//! (`rtcm_common::esbc`: each signal's S value as DF408) and read back
//! by two independent NMEA parsers (the `nmea` crate and pynmea2).
//!
//!     cargo test --release -p host-tests --test stream_cn0 -- --nocapture

mod rtcm_common;

use std::collections::BTreeMap;
use std::io::Write as _;
use std::process::{Command, Stdio};

use raim_core::{Config, SatId, System};
use raim_gnss::ObsData;
use raim_nav::rtcm::{FormedEpoch, StreamReceiver};
use rtcm_common::esbc::{data, esbc_stream, EPOCHS, ESBC_WEEK, OBS};
use rtcm_common::{frames, in_window_week, MASK_RAD};

/// The GSV C/N0 of each satellite at each of ESBC's first `EPOCHS`
/// epochs, from the RINEX: the S observable of the first code of the
/// stream's pair for its system (S1C for GPS C1C+C2W and Galileo
/// C1C+C5Q, S2I for BeiDou C2I+C6I; a C2I-only BeiDou satellite the
/// same), rounded half away from zero to whole dB-Hz (`f64::round`).
fn rinex_cn0() -> Vec<BTreeMap<SatId, u8>> {
    let obs = ObsData::load(&data(OBS)).unwrap();
    obs.epochs
        .iter()
        .take(EPOCHS)
        .map(|e| {
            e.sats
                .iter()
                .filter_map(|(id, codes)| {
                    let first = match id.system {
                        System::Gps | System::Galileo => "C1C",
                        System::Beidou => "C2I",
                        _ => return None,
                    };
                    let s = codes.iter().find(|c| c.code == first)?.cn0_dbhz?;
                    Some((*id, s.round() as u8))
                })
                .collect()
        })
        .collect()
}

/// The device's stream receiver on the ESBC stream: every satellite of
/// every formed epoch carries the RINEX S value of its first signal, to
/// the whole dB-Hz (DF408 holds it to 2^-4 dB-Hz).
///
/// Verifies: RX-CN0
#[test]
fn device_stream_receiver_carries_the_rinex_cn0() {
    let (bytes, _) = esbc_stream(0);
    let want = rinex_cn0();
    let sigmas = raim_nav::ranging::StreamSigmas::Snapshot(Config::default().sigma_model);
    let mut dev = Box::new(StreamReceiver::<64, 256>::new(ESBC_WEEK - 52));
    let mut formed = FormedEpoch::<64> {
        time_gps_s: 0.0,
        reference_m: None,
        sats: heapless::Vec::new(),
        cn0_dbhz: heapless::Vec::new(),
        rates: heapless::Vec::new(),
        rejected: 0,
    };
    let (mut k, mut checked) = (0, 0);
    for f in frames(&bytes) {
        if let Some(r) = dev.on_frame(f, &sigmas, MASK_RAD, &mut formed) {
            r.unwrap();
            assert_eq!(formed.cn0_dbhz.len(), formed.sats.len());
            for (s, c) in formed.sats.iter().zip(&formed.cn0_dbhz) {
                assert_eq!(Some(c), want[k].get(&s.id), "epoch {k} {:?}", s.id);
                checked += 1;
            }
            k += 1;
        }
    }
    assert_eq!(k, EPOCHS);
    println!("{checked} satellite C/N0 values over {k} epochs: the RINEX S, rounded");
    assert!(checked >= 20 * EPOCHS);
}

struct Sink(Vec<u8>);
impl embedded_io::ErrorType for Sink {
    type Error = core::convert::Infallible;
}
impl embedded_io::Write for Sink {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        self.0.extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
}

fn system_of_talker(t: &str) -> System {
    match t {
        "GP" => System::Gps,
        "GA" => System::Galileo,
        "GB" => System::Beidou,
        other => panic!("talker {other}"),
    }
}

/// The unit's GSV on the ESBC stream (a host `Server`, configured with
/// `Config::default()`, the snapshot monitor): every satellite's C/N0 is
/// the RINEX S value of its first signal, as both the `nmea` crate and
/// pynmea2 read it, at every epoch.
///
/// Verifies: RX-CN0
#[test]
fn unit_gsv_carries_the_stream_cn0() {
    let week = in_window_week();
    let (bytes, _) = esbc_stream(week - ESBC_WEEK);
    let want = rinex_cn0();
    let mut server = Box::new(raim_server::Server::new());
    server.take_runtime_config(Config::default()).unwrap();
    let (mut link, mut nmea_out) = (Sink(Vec::new()), Sink(Vec::new()));
    for &b in &bytes {
        server
            .on_byte(b, &mut link, &mut nmea_out, &mut raim_server::NoPlatform)
            .unwrap();
    }
    let text = String::from_utf8(nmea_out.0).unwrap();
    let lines: Vec<&str> = text.lines().map(str::trim_end).collect();
    // One epoch per RMC; its GSV sentences, read by the `nmea` crate.
    let mut epochs: Vec<Vec<(SatId, Option<u8>)>> = Vec::new();
    let mut gsv_lines = Vec::new();
    for l in &lines {
        if &l[3..6] == "RMC" {
            epochs.push(Vec::new());
        }
        if &l[3..6] != "GSV" {
            continue;
        }
        gsv_lines.push(*l);
        let system = system_of_talker(&l[1..3]);
        let nmea::ParseResult::GSV(g) = nmea::parse_str(l).unwrap() else {
            panic!("{l}");
        };
        for s in g.sats_info.iter().flatten() {
            let id = SatId::new(system, s.prn() as u8);
            epochs
                .last_mut()
                .unwrap()
                .push((id, s.snr().map(|v| v as u8)));
        }
    }
    assert_eq!(epochs.len(), EPOCHS);
    let mut checked = 0;
    for (k, e) in epochs.iter().enumerate() {
        assert!(e.len() >= 20, "epoch {k}: {e:?}");
        for (id, snr) in e {
            assert_eq!(snr.as_ref(), want[k].get(id), "epoch {k} {id:?}");
            checked += 1;
        }
    }
    // pynmea2 reads the same C/N0 from the same sentences.
    // (pynmea2 1.19 knows no NMEA 4.11 signal ID: in a GSV of fewer than
    // four satellites it is read as the next PRN, so only the satellites
    // the sentence holds by its counts are taken.)
    let script = "import sys, pynmea2\n\
for line in sys.stdin:\n    m = pynmea2.parse(line.strip(), check=True)\n    \
n = min(4, int(m.num_sv_in_view) - 4 * (int(m.msg_num) - 1))\n    \
for k in range(1, n + 1):\n        \
print(m.talker, int(getattr(m, 'sv_prn_num_%d' % k)), getattr(m, 'snr_%d' % k))\n";
    let mut py = Command::new("python3")
        .args(["-c", script])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("python3");
    let input: String = gsv_lines.iter().map(|s| format!("{s}\r\n")).collect();
    py.stdin
        .take()
        .unwrap()
        .write_all(input.as_bytes())
        .unwrap();
    let out = py.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "pynmea2: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let py_cn0: Vec<(SatId, Option<u8>)> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| {
            let f: Vec<&str> = l.split(' ').collect();
            (
                SatId::new(system_of_talker(f[0]), f[1].parse().unwrap()),
                f[2].parse().ok(),
            )
        })
        .collect();
    let crate_cn0: Vec<(SatId, Option<u8>)> = epochs.concat();
    assert_eq!(py_cn0, crate_cn0);
    println!(
        "{EPOCHS} stream epochs, {} GSV sentences, {checked} satellites: C/N0 the RINEX S rounded, the nmea crate and pynmea2 alike",
        gsv_lines.len()
    );
}
