//! C/N0 in the replay's GSV (issue 34, "NMEA"): `raim replay --nmea only`
//! on a RINEX 3 file writes each satellite's S observable of the code it
//! is ranged with, rounded to whole dB-Hz; on a RINEX 2 file without S
//! observables the field stays empty. Read back by pynmea2, an NMEA
//! parser independent of the writer.
//!
//!     cargo test --release -p raim-tool --test cli_replay_cn0 -- --nocapture

use std::collections::BTreeMap;
use std::io::Write as _;
use std::process::{Command, Stdio};

use raim_core::{SatId, System};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data");

/// `raim replay ... --nmea only`: its sentences.
fn nmea(args: &[&str]) -> Vec<String> {
    let out = Command::new(env!("CARGO_BIN_EXE_raim"))
        .arg("replay")
        .args(args)
        .args(["--nmea", "only"])
        .output()
        .expect("spawn raim");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| l.trim_end().to_string())
        .collect()
}

/// Per epoch (one per RMC), each GSV satellite and its C/N0 as pynmea2
/// reads them (pynmea2 1.19 knows no NMEA 4.11 signal ID, which it would
/// read as a PRN in a GSV of fewer than four satellites: only the
/// satellites the sentence holds by its counts are taken).
fn gsv_cn0(lines: &[String]) -> Vec<Vec<(SatId, Option<u8>)>> {
    let script = "import sys, pynmea2\n\
for line in sys.stdin:\n    m = pynmea2.parse(line.strip(), check=True)\n    \
if m.sentence_type == 'RMC':\n        print('RMC'); continue\n    \
if m.sentence_type != 'GSV': continue\n    \
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
    let input: String = lines.iter().map(|s| format!("{s}\r\n")).collect();
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
    let mut epochs: Vec<Vec<(SatId, Option<u8>)>> = Vec::new();
    for l in String::from_utf8(out.stdout).unwrap().lines() {
        if l == "RMC" {
            epochs.push(Vec::new());
            continue;
        }
        let f: Vec<&str> = l.split(' ').collect();
        let system = match f[0] {
            "GP" => System::Gps,
            "GA" => System::Galileo,
            "GB" => System::Beidou,
            other => panic!("talker {other}"),
        };
        epochs
            .last_mut()
            .expect("an RMC first")
            .push((SatId::new(system, f[1].parse().unwrap()), f[2].parse().ok()));
    }
    epochs
}

/// ESBC (RINEX 3.04, S observables in dB-Hz), the first ten minutes,
/// single codes GPS C1C, Galileo C1C, BeiDou C2I: every GSV satellite's
/// C/N0 is its S1C (S2I) rounded half away from zero (`f64::round` of the
/// value read from the RINEX); 0759 (RINEX 2.10, no S): every C/N0 field
/// empty.
///
/// Verifies: RX-CN0
#[test]
fn replay_gsv_carries_the_rinex_s_observables() {
    let obs = format!("{DATA}/ESBC00DNK_R_20201770000_03H_30S_MO.rnx.gz");
    let nav = format!("{DATA}/ESBC00DNK_R_20201770000_01D_MN.rnx.gz");
    let lines = nmea(&[
        "--obs",
        &obs,
        "--nav",
        &nav,
        "--systems",
        "GEC",
        "--code",
        "G=C1C",
        "--code",
        "E=C1C",
        "--code",
        "C=C2I",
        "--end",
        "00:10:00",
    ]);
    let got = gsv_cn0(&lines);
    let rinex = raim_gnss::ObsData::load(std::path::Path::new(&obs)).unwrap();
    assert_eq!(got.len(), 21);
    let mut checked = 0;
    for (k, (e, o)) in got.iter().zip(&rinex.epochs).enumerate() {
        let want: BTreeMap<SatId, u8> = o
            .sats
            .iter()
            .filter_map(|(id, codes)| {
                let code = if id.system == System::Beidou {
                    "C2I"
                } else {
                    "C1C"
                };
                let s = codes.iter().find(|c| c.code == code)?.cn0_dbhz?;
                Some((*id, s.round() as u8))
            })
            .collect();
        assert!(e.len() >= 15, "epoch {k}: {e:?}");
        for (id, cn0) in e {
            assert_eq!(cn0.as_ref(), want.get(id), "epoch {k} {id:?}");
            checked += 1;
        }
    }
    println!(
        "ESBC: {} epochs, {checked} GSV satellites, each C/N0 its S observable",
        got.len()
    );

    let lines = nmea(&[
        "--obs",
        &format!("{DATA}/07590920.05o"),
        "--nav",
        &format!("{DATA}/07590920.05n"),
        "--end",
        "00:10:00",
    ]);
    let got = gsv_cn0(&lines);
    assert!(!got.is_empty());
    let n: usize = got.iter().map(Vec::len).sum();
    assert!(n >= 4 * got.len());
    assert!(got.iter().flatten().all(|(_, c)| c.is_none()), "{got:?}");
    println!(
        "0759 (RINEX 2, no S): {} epochs, {n} GSV satellites, every C/N0 empty",
        got.len()
    );
}
