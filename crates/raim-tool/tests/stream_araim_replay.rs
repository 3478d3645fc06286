//! The unit's ARAIM on a receiver stream against `raim replay --araim` on
//! the RINEX the stream was made from (issue 34's goal: ARAIM available
//! where the replay says it is, with the same protection levels).
//!
//! The stream: ESBC's first 80 epochs (G+E+C) as MSM7 by host-tests'
//! committed generator (`host-tests/tests/rtcm_common/esbc.rs`, included
//! here), with only the satellites that carry both signals of their
//! system's iono-free pair, so that it holds the satellites the replay
//! ranges with `--code G=C1C+C2W --code E=C1C+C5Q --code C=C2I+C6I` (the
//! full stream also sends ESBC's three C2I-only BeiDou satellites
//! single-frequency, which that replay drops: docs/RECEIVERS.md "Against
//! `raim replay --araim`"). It goes through raim-server's `Server` (the
//! unit's code on the host, f32 engine) configured with
//! `Config::default()` and an `Ism` frame of the replay's default ISM
//! values; the replay is the `raim` binary's. The stream sigmas of an
//! ARAIM epoch and the replay's satellite models come from the same
//! function, `raim_nav::ranging::araim_curves`.
//!
//!     cargo test --release -p raim-tool --test stream_araim_replay -- --nocapture

#[allow(dead_code)]
#[path = "../../../host-tests/tests/rtcm_common/esbc.rs"]
mod esbc;

use std::process::Command;

use raim_core::{Config, Decision, SatId, System};
use raim_proto::araim_msg::{
    AraimAnswer, AraimCommandRef, IsmFrameRef, IsmSat, WireAraimConfig, WireAraimResult, WireFde,
};
use raim_proto::message::{CommandRef, RequestRef, Response, ResponseBody};
use serde_json::Value;

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data");

/// The protection levels of the unit (f32 engine) against the replay's
/// (f64), relative: docs/F32_EQUIVALENCE.md's tolerance on HPL and VPL
/// where the epoch is Ok or Excluded (1e-2 relative), here on every
/// epoch's all-in-view PLs and on the PLs in force where both have them.
const PL_TOL_REL: f64 = 1e-2;
/// The epoch times of the two, s: the stream's MSM time of week is the
/// RINEX epoch's to the millisecond.
const TIME_TOL_S: f64 = 1e-3;

/// The replay's ISM values (`raim replay --araim`'s defaults: the ADD's
/// nominal sigma_URA 0.75 m, sigma_URE 0.5 m, b_nom 0.5 m, P_sat 1e-5,
/// P_const 1e-4) for every satellite the stream carries.
fn ism(carried: &[esbc::Carried]) -> (Vec<IsmSat>, [Option<f64>; 5]) {
    let mut ids: Vec<SatId> = carried
        .iter()
        .flat_map(|(_, v)| v.iter().map(|(id, _, _)| *id))
        .collect();
    ids.sort_by_key(|id| (id.system.index(), id.prn));
    ids.dedup();
    let mut p_const = [None; 5];
    for id in &ids {
        p_const[id.system.index()] = Some(1e-4);
    }
    let sats = ids
        .into_iter()
        .map(|id| IsmSat {
            id,
            sigma_ura_m: 0.75,
            sigma_ure_m: 0.5,
            b_nom_m: 0.5,
            p_sat: 1e-5,
        })
        .collect();
    (sats, p_const)
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

/// `bytes` through `server`: its answers.
fn feed(server: &mut raim_server::Server, bytes: &[u8]) -> Vec<Response> {
    let (mut link, mut nmea) = (Sink(Vec::new()), Sink(Vec::new()));
    for &b in bytes {
        server
            .on_byte(b, &mut link, &mut nmea, &mut raim_server::NoPlatform)
            .unwrap();
    }
    let mut rx = Box::new(raim_proto::frame::FrameReceiver::<
        { raim_proto::MAX_RESPONSE_FRAME },
    >::new());
    link.0
        .iter()
        .filter_map(|&b| {
            rx.push(b)
                .map(|p| postcard::from_bytes(p.unwrap()).unwrap())
        })
        .collect()
}

/// The stream's ARAIM answers from a host `Server` configured at run time
/// with `Config::default()` and sent the ISM, then the stream.
fn stream_answers(bytes: &[u8], ism: &(Vec<IsmSat>, [Option<f64>; 5])) -> Vec<WireAraimResult> {
    let mut server = Box::new(raim_server::Server::new());
    server.take_runtime_config(Config::default()).unwrap();
    let frame = raim_qemu::encode_request(&RequestRef {
        seq: 0,
        command: CommandRef::Araim(AraimCommandRef::Ism(IsmFrameRef {
            config: WireAraimConfig::default(),
            p_const: ism.1,
            sats: &ism.0,
        })),
    })
    .unwrap();
    let a = feed(&mut server, &frame);
    assert!(
        matches!(
            a[..],
            [Response {
                body: ResponseBody::Araim(AraimAnswer::IsmAccepted { .. }),
                ..
            }]
        ),
        "{a:?}"
    );
    feed(&mut server, bytes)
        .into_iter()
        .map(|r| {
            assert_eq!(r.seq, None, "a stream epoch's answer is unasked");
            match r.body {
                ResponseBody::Araim(AraimAnswer::Result(w)) => w,
                other => panic!("not an ARAIM result: {other:?}"),
            }
        })
        .collect()
}

/// `raim replay --araim` on ESBC's RINEX, the stream's 80 epochs, the
/// stream's pairs: the per-epoch records and the summary.
fn replay() -> (Vec<Value>, Value) {
    let obs = format!("{DATA}/{}", esbc::OBS);
    let nav = format!("{DATA}/{}", esbc::NAV);
    replay_with(&[
        "--obs",
        &obs,
        "--nav",
        &nav,
        "--systems",
        "GEC",
        "--code",
        "G=C1C+C2W",
        "--code",
        "E=C1C+C5Q",
        "--code",
        "C=C2I+C6I",
        "--end",
        "00:39:30",
    ])
}

/// `raim replay --araim --json` with the sources `args`.
fn replay_with(args: &[&str]) -> (Vec<Value>, Value) {
    let out = Command::new(env!("CARGO_BIN_EXE_raim"))
        .arg("replay")
        .args(args)
        .args(["--araim", "--json"])
        .output()
        .expect("spawn raim");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let lines: Vec<Value> = String::from_utf8(out.stdout)
        .expect("utf8")
        .lines()
        .map(|l| serde_json::from_str(l).expect("json"))
        .collect();
    let (summary, recs) = lines.split_last().expect("a summary");
    (recs.to_vec(), summary["araim_summary"].clone())
}

/// The replay record's FDE name of a wire FDE outcome (`replay::araim`'s
/// `fill`).
fn fde_name(f: &WireFde) -> &'static str {
    match f {
        WireFde::NoFault => "no_fault",
        WireFde::Excluded { .. } => "excluded",
        WireFde::Ambiguous { .. } => "alarm_ambiguous",
        WireFde::NoCandidate => "alarm_no_candidate",
        WireFde::BudgetExceeded { .. } => "alarm_budget_exceeded",
        WireFde::NotTested => "not_tested",
        WireFde::NotAttempted { .. } => "alarm_not_attempted",
    }
}

fn name(id: SatId) -> String {
    format!("{}{:02}", id.system.letter(), id.prn)
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(f64::MIN_POSITIVE)
}

/// Epoch for epoch on ESBC's 80 epochs: the same time, the same number of
/// fault modes (the same satellites and priors), the same detection test
/// outcome, FDE outcome, excluded satellites, decision class and ARAIM
/// availability; the all-in-view VPL and HPL, and the VPL and HPL in
/// force where the replay has them, within `PL_TOL_REL`.
///
/// Verifies: RX-ARAIM-REPLAY
#[test]
fn stream_araim_equals_the_rinex_replay_epoch_for_epoch() {
    let week = raim_server::stream::PIVOT_WEEK + 26;
    let delta_weeks = week - esbc::ESBC_WEEK;
    let (bytes, carried) = esbc::esbc_stream_pairs_only(delta_weeks);
    let ism = ism(&carried);
    let got = stream_answers(&bytes, &ism);
    let (want, summary) = replay();
    assert_eq!(got.len(), esbc::EPOCHS);
    assert_eq!(want.len(), esbc::EPOCHS);

    let (worst_all, worst_in_force, available, detections, mean_v, mean_h) =
        compare(&got, &want, delta_weeks);
    let decisions = |d: Decision| got.iter().filter(|w| w.decision == d).count();
    println!(
        "stream vs replay, {} epochs: the same modes, detections, FDE outcomes, exclusions and availability at every epoch; \
         stream {} Ok / {} Excluded / {} Unavailable / {} Alarm, {available} available, {detections} detections \
         (replay: {} available, {} alarms, {} exclusions, {} detections); \
         stream mean VPL/HPL {:.2}/{:.2} m (replay {:.2}/{:.2} m); worst relative PL difference {:.1e} all in view, {:.1e} in force",
        got.len(),
        decisions(Decision::Ok),
        decisions(Decision::Excluded),
        decisions(Decision::Unavailable),
        decisions(Decision::Alarm),
        summary["available"],
        summary["alarms"],
        summary["exclusions"],
        summary["false_detections"],
        mean_v,
        mean_h,
        summary["mean_vpl_m"].as_f64().unwrap(),
        summary["mean_hpl_m"].as_f64().unwrap(),
        worst_all,
        worst_in_force,
    );
    assert_eq!(available as u64, summary["available"].as_u64().unwrap());
    // Both systems present in the stream (the pairs-only filter keeps the
    // replay's satellites, not fewer).
    for sys in [System::Gps, System::Galileo, System::Beidou] {
        assert!(ism.0.iter().any(|s| s.id.system == sys), "{sys:?}");
    }
}

/// Epoch for epoch, the unit's answers `got` against the replay's records
/// `want` (the replay dated `delta_weeks` earlier): the same time, number
/// of fault modes, detection outcome, FDE outcome, excluded satellites
/// and availability; the all-in-view VPL and HPL, and those in force where
/// the replay has them, within `PL_TOL_REL`. Returns the worst relative
/// PL differences (all in view, in force), the available epochs, the
/// detections and the mean VPL and HPL in force.
fn compare(
    got: &[WireAraimResult],
    want: &[Value],
    delta_weeks: i64,
) -> (f64, f64, usize, usize, f64, f64) {
    let (mut worst_all, mut worst_in_force) = (0.0f64, 0.0f64);
    let (mut available, mut detections) = (0usize, 0usize);
    let (mut sum_v, mut sum_h, mut n_pl) = (0.0, 0.0, 0usize);
    for (k, (w, r)) in got.iter().zip(want).enumerate() {
        let t_gps = r["time_gps_s"].as_f64().unwrap() + delta_weeks as f64 * 604_800.0;
        let t_unix = raim_nav::time::unix_utc_s(t_gps);
        assert!((w.time_s - t_unix).abs() <= TIME_TOL_S, "epoch {k}");
        let a = &w.all_in_view;
        assert_eq!(
            u64::from(a.modes),
            r["modes"].as_u64().unwrap(),
            "epoch {k}: modes"
        );
        assert_eq!(
            a.detection_passed,
            r["detection_passed"].as_bool().unwrap(),
            "epoch {k}: detection"
        );
        assert_eq!(fde_name(&w.fde), r["fde"].as_str().unwrap(), "epoch {k}");
        let excluded: Vec<String> = w.excluded.iter().map(|id| name(*id)).collect();
        let want_excluded: Vec<String> = r["excluded"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| s.as_str().unwrap().to_string())
            .collect();
        assert_eq!(excluded, want_excluded, "epoch {k}");
        let avail = matches!(w.decision, Decision::Ok | Decision::Excluded);
        assert_eq!(avail, r["available"].as_bool().unwrap(), "epoch {k}");
        available += usize::from(avail);
        detections += usize::from(!a.detection_passed);
        for (g, key) in [(a.vpl_m, "vpl_all_m"), (a.hpl_m, "hpl_all_m")] {
            let e = rel(g, r[key].as_f64().unwrap());
            assert!(e <= PL_TOL_REL, "epoch {k}: {key} {g} against {}", r[key]);
            worst_all = worst_all.max(e);
        }
        if let (Some(v), Some(h)) = (r["vpl_m"].as_f64(), r["hpl_m"].as_f64()) {
            let f = w.in_force();
            for (g, x, key) in [(f.vpl_m, v, "vpl_m"), (f.hpl_m, h, "hpl_m")] {
                let e = rel(g, x);
                assert!(e <= PL_TOL_REL, "epoch {k}: {key} {g} against {x}");
                worst_in_force = worst_in_force.max(e);
            }
            sum_v += f.vpl_m;
            sum_h += f.hpl_m;
            n_pl += 1;
        }
    }
    (
        worst_all,
        worst_in_force,
        available,
        detections,
        sum_v / n_pl as f64,
        sum_h / n_pl as f64,
    )
}

/// The host's own stream replay, `raim replay --rtcm3 FILE --araim`, on
/// the full ESBC stream (with its three single-frequency BeiDou
/// satellites) against the unit's answers to the same bytes: the replay
/// forms a stream epoch's sigmas under ARAIM as the unit does
/// (`StreamSigmas::Araim`), so the two agree epoch for epoch as above.
///
/// Verifies: RX-ARAIM-REPLAY
#[test]
fn host_stream_replay_under_araim_equals_the_unit() {
    let week = raim_server::stream::PIVOT_WEEK + 26;
    let delta_weeks = week - esbc::ESBC_WEEK;
    let (bytes, carried) = esbc::esbc_stream(delta_weeks);
    let ism = ism(&carried);
    let got = stream_answers(&bytes, &ism);
    let file = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("raim-esbc-araim.rtcm3");
    std::fs::write(&file, &bytes).unwrap();
    let (want, summary) = replay_with(&["--rtcm3", file.to_str().unwrap()]);
    let _ = std::fs::remove_file(&file);
    assert_eq!(got.len(), esbc::EPOCHS);
    assert_eq!(want.len(), esbc::EPOCHS);
    // The replay's records are dated by the stream itself (the moved week).
    let (worst_all, worst_in_force, available, detections, mean_v, mean_h) =
        compare(&got, &want, 0);
    println!(
        "raim replay --rtcm3 --araim vs the unit on the full ESBC stream, {} epochs: the same modes, detections, FDE outcomes, exclusions and availability at every epoch; \
         {available} available, {detections} detections (replay summary: {} available, {} alarms); mean VPL/HPL {mean_v:.2}/{mean_h:.2} m; worst relative PL difference {worst_all:.1e} all in view, {worst_in_force:.1e} in force",
        got.len(),
        summary["available"],
        summary["alarms"],
    );
}
