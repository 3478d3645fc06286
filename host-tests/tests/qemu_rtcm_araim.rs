//! ARAIM on the unit's own stream epochs (raim-server `stream`, "Which
//! monitor": an ISM in force makes each stream epoch an `Araim(Ranges)`
//! epoch of the one ARAIM path): the G+E+C stream generated from ESBC's
//! RINEX (`rtcm_common::esbc`) written into the link UART of the firmware
//! under QEMU, with an ISM taken as `qemu_araim.rs` sends it (an `Ism`
//! frame to a unit configured at run time), clean and with faults written
//! into the stream by `raim_recv::msm_fault` (`raim rtcm-fault`).
//!
//! References:
//! - the same frames (configuration, ISM, stream) through raim-server's
//!   `Server` on the host (the same core on x86): the unit's answers and
//!   NMEA sentences, byte for byte;
//! - the host's own epochs (`rtcm_common::host_epochs_with`: raim-recv's
//!   reader and raim-gnss's preparation, run causally, with the ARAIM
//!   stream sigmas) sent to a host `Server` as `Araim(Ranges)` requests:
//!   the same answer bodies, epoch for epoch;
//! - the injected fault: a 30 m step on one Galileo satellite is excluded
//!   (or alarmed) at every epoch from its onset, and before it the
//!   outcomes are the clean stream's (whose few detections are the
//!   nominal model's misfit to ESBC's BeiDou ranges, as in `raim replay
//!   --araim` on the RINEX: docs/RECEIVERS.md); a Galileo constellation fault (the Galileo
//!   solution displaced 60 m upwards, `raim_gnss::faults::constellation_bias`)
//!   is never passed: the constellation fault mode excludes every Galileo
//!   satellite (with service on G+C, or without it when their protection
//!   levels exceed the alert limits), or the epoch is an alarm.
//!
//!     cargo test --release -p host-tests --test qemu_rtcm_araim -- --nocapture

mod qemu_common;
mod rtcm_common;

use std::collections::{BTreeMap, BTreeSet};
use std::time::Duration;

use qemu_common::{stream_session_on, Sink};
use raim_core::{Config, Decision, RangeObservation, SatId, System};
use raim_proto::araim_msg::{
    AraimAnswer, AraimCommandRef, IsmFrameRef, IsmSat, WireAraimConfig, WireAraimResult,
};
use raim_proto::message::{CommandRef, RequestRef, Response, ResponseBody};
use raim_qemu::{Machine, QemuSession};
use rtcm_common::esbc::{esbc_stream, EPOCHS, ESBC_WEEK};
use rtcm_common::{host_epochs_with, in_window_week, HostEpoch};

/// The firmware's stack goal for every path (BENCHMARKS.md "Stack"), B.
const STACK_GOAL_BYTES: u32 = 16 * 1024;
/// How long the unit may take over the whole stream (80 ARAIM epochs, with
/// exclusions): a hang's deadline, not a timing.
const STREAM_TIMEOUT: Duration = Duration::from_secs(900);
/// The fault onset, s after the first epoch (epoch 20 of 80).
const ONSET_S: f64 = 600.0;

/// The ESBC stream in this build's dating window, and the host's epochs of
/// it with the ARAIM stream sigmas (raim-server's `stream::stream_sigmas`:
/// the ARAIM curves of each satellite's signal pair, as `raim replay
/// --araim` models it).
fn stream() -> (Vec<u8>, Vec<HostEpoch>) {
    let week = in_window_week();
    let (bytes, _) = esbc_stream(week - ESBC_WEEK);
    let sigmas = raim_server::stream::stream_sigmas(Some(&Config::default()), true);
    let (host, counts) = host_epochs_with(&bytes, week + 1, &sigmas);
    assert_eq!(counts.epochs as usize, EPOCHS);
    (bytes, host)
}

/// The ISM: an entry for every satellite of the host's epochs, sigma_URA
/// 0.75 m, sigma_URE 0.5 m, b_nom 0.5 m, P_sat 1e-5 (the ADD's nominal
/// values, `raim replay --araim`'s defaults), P_const 1e-4 for each
/// constellation.
fn ism(host: &[HostEpoch]) -> (Vec<IsmSat>, [Option<f64>; 5]) {
    let ids: BTreeSet<(usize, u8)> = host
        .iter()
        .flat_map(|h| h.obs.iter().map(|s| (s.id.system.index(), s.id.prn)))
        .collect();
    let mut p_const = [None; 5];
    let sats = ids
        .into_iter()
        .map(|(k, prn)| {
            let system = System::ALL[k];
            p_const[k] = Some(1e-4);
            IsmSat {
                id: SatId::new(system, prn),
                sigma_ura_m: 0.75,
                sigma_ure_m: 0.5,
                b_nom_m: 0.5,
                p_sat: 1e-5,
            }
        })
        .collect();
    (sats, p_const)
}

fn ism_command<'a>(sats: &'a [IsmSat], p_const: [Option<f64>; 5]) -> CommandRef<'a> {
    CommandRef::Araim(AraimCommandRef::Ism(IsmFrameRef {
        config: WireAraimConfig::default(),
        p_const,
        sats,
    }))
}

/// A host `Server` configured as a QEMU session configures the unit
/// (`Configure(Config::default())` at run time).
fn host_server() -> Box<raim_server::Server> {
    let mut s = Box::new(raim_server::Server::new());
    s.take_runtime_config(Config::default()).unwrap();
    s
}

/// `bytes` through a host server: its answers and NMEA lines.
fn feed(server: &mut raim_server::Server, bytes: &[u8]) -> (Vec<Response>, Vec<String>) {
    let (mut link, mut nmea) = (Sink(Vec::new()), Sink(Vec::new()));
    for &b in bytes {
        server
            .on_byte(b, &mut link, &mut nmea, &mut raim_server::NoPlatform)
            .unwrap();
    }
    let mut rx = Box::new(raim_proto::frame::FrameReceiver::<
        { raim_proto::MAX_RESPONSE_FRAME },
    >::new());
    let answers = link
        .0
        .iter()
        .filter_map(|&b| {
            rx.push(b)
                .map(|p| postcard::from_bytes(p.unwrap()).unwrap())
        })
        .collect();
    let nmea = String::from_utf8(nmea.0)
        .unwrap()
        .lines()
        .map(|l| l.trim_end().to_string())
        .collect();
    (answers, nmea)
}

fn request(seq: u32, command: CommandRef<'_>) -> Vec<u8> {
    raim_qemu::encode_request(&RequestRef { seq, command }).unwrap()
}

/// postcard bytes of a response: the bit-exact comparison (NaN included).
fn response_bytes(r: &Response) -> Vec<u8> {
    let mut buf = vec![0u8; raim_proto::MAX_RESPONSE_PAYLOAD];
    postcard::to_slice(r, &mut buf).unwrap().to_vec()
}

/// The host server's answers to the ISM and then the stream: the ISM's
/// answer and the stream's unasked ones, with the stream's NMEA.
fn host_run(ism: &(Vec<IsmSat>, [Option<f64>; 5]), bytes: &[u8]) -> (Vec<Response>, Vec<String>) {
    let mut server = host_server();
    let (a, _) = feed(&mut server, &request(0, ism_command(&ism.0, ism.1)));
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
}

/// The host's epochs as `Araim(Ranges)` requests to a host server: the
/// answer bodies.
fn host_epoch_answers(
    ism: &(Vec<IsmSat>, [Option<f64>; 5]),
    host: &[HostEpoch],
) -> Vec<ResponseBody> {
    let mut server = host_server();
    feed(&mut server, &request(0, ism_command(&ism.0, ism.1)));
    host.iter()
        .enumerate()
        .map(|(k, h)| {
            let time_s = raim_nav::time::unix_utc_s(h.prepared.time_gps_s);
            let (mut a, _) = feed(
                &mut server,
                &request(
                    k as u32 + 1,
                    CommandRef::Araim(AraimCommandRef::Ranges {
                        time_s,
                        apriori_m: h.prepared.reference_m,
                        sats: &h.obs,
                    }),
                ),
            );
            assert_eq!(a.len(), 1, "{a:?}");
            a.remove(0).body
        })
        .collect()
}

/// The unit fed the ISM and then the stream: its unasked answers, NMEA
/// lines and final `Status`.
fn unit_run(
    ism: &(Vec<IsmSat>, [Option<f64>; 5]),
    bytes: &[u8],
    n: usize,
    nmea_lines: usize,
) -> (Vec<Response>, Vec<String>, raim_proto::message::Status) {
    let mut fw: QemuSession = stream_session_on(Machine::Mps2An386);
    let body = fw.call(ism_command(&ism.0, ism.1)).unwrap();
    assert!(
        matches!(body, ResponseBody::Araim(AraimAnswer::IsmAccepted { .. })),
        "{body:?}"
    );
    fw.drain_nmea();
    for chunk in bytes.chunks(4096) {
        fw.send_raw(chunk).unwrap();
    }
    let deadline = std::time::Instant::now() + STREAM_TIMEOUT;
    let mut out = Vec::new();
    while out.len() < n {
        let left = deadline.saturating_duration_since(std::time::Instant::now());
        let r = fw
            .recv(left.max(Duration::from_millis(1)))
            .unwrap_or_else(|e| panic!("after {} answers: {e}", out.len()));
        assert_eq!(r.seq, None, "a stream epoch's answer is unasked: {r:?}");
        out.push(r);
    }
    // The NMEA UART is read by its own thread: wait, with a deadline only
    // a hang reaches, for the sentences the host wrote.
    let mut nmea = fw.drain_nmea();
    let deadline = std::time::Instant::now() + Duration::from_secs(30);
    while nmea.len() < nmea_lines && std::time::Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
        nmea.extend(fw.drain_nmea());
    }
    let nmea = nmea.iter().map(|s| s.trim_end().to_string()).collect();
    let status = fw.status().unwrap();
    (out, nmea, status)
}

fn araim_result(r: &ResponseBody) -> &WireAraimResult {
    match r {
        ResponseBody::Araim(AraimAnswer::Result(w)) => w,
        other => panic!("not an ARAIM result: {other:?}"),
    }
}

/// Per epoch: (time from the first epoch s, decision, excluded).
fn outcomes(answers: &[Response], host: &[HostEpoch]) -> Vec<(f64, Decision, Vec<SatId>)> {
    let t0 = host[0].prepared.time_gps_s;
    answers
        .iter()
        .zip(host)
        .map(|(a, h)| {
            let w = araim_result(&a.body);
            (
                h.prepared.time_gps_s - t0,
                w.decision,
                w.excluded.iter().copied().collect(),
            )
        })
        .collect()
}

/// The Galileo satellite of the lowest PRN in every host epoch.
fn galileo_in_all(host: &[HostEpoch]) -> SatId {
    let mut n = BTreeMap::<SatId, usize>::new();
    for h in host {
        for s in &h.obs {
            *n.entry(s.id).or_default() += 1;
        }
    }
    n.into_iter()
        .find(|(id, k)| id.system == System::Galileo && *k == host.len())
        .map(|(id, _)| id)
        .expect("a Galileo satellite in every epoch")
}

/// `bytes` with a step of `bias_m` on `sat` from `ONSET_S` on
/// (`raim_recv::msm_fault`, the `--fault` vocabulary).
fn with_step(bytes: &[u8], sat: SatId, bias_m: f64) -> Vec<u8> {
    let first = raim_recv::msm_fault::first_msm_gps_s(bytes).unwrap();
    let spec = format!(
        "step:{}{:02}:{bias_m}@+{ONSET_S}",
        sat.system.letter(),
        sat.prn
    );
    let plan = raim_gnss::faults::FaultPlan {
        faults: vec![raim_gnss::faults::FaultPlan::parse_cli(&spec, first).unwrap()],
        seed: 0,
    };
    raim_recv::msm_fault::fault_stream(bytes, &plan)
        .unwrap()
        .bytes
}

/// The Galileo constellation fault: from `ONSET_S` on, each Galileo
/// satellite's ranges carry `raim_gnss::faults::constellation_bias` with
/// the Galileo solution displaced by `shift_enu_m` at the station (the
/// lines of sight of the host's epochs), written into the stream.
fn with_galileo_shift(bytes: &[u8], host: &[HostEpoch], shift_enu_m: [f64; 3]) -> Vec<u8> {
    let first = raim_recv::msm_fault::first_msm_gps_s(bytes).unwrap();
    let table = galileo_shift_table(host, shift_enu_m);
    raim_recv::msm_fault::bias_stream(bytes, |t, sats| {
        let k = (t - first).round() as i64;
        for s in sats.iter_mut() {
            s.pseudorange_m += table.get(&(k, s.id)).copied().unwrap_or(0.0);
        }
    })
    .unwrap()
    .bytes
}

/// The biases of [`with_galileo_shift`], keyed by (s from the first
/// epoch, satellite), from the host's epochs.
fn galileo_shift_table(host: &[HostEpoch], shift_enu_m: [f64; 3]) -> BTreeMap<(i64, SatId), f64> {
    let t0 = host[0].prepared.time_gps_s;
    let mut table = BTreeMap::<(i64, SatId), f64>::new();
    for h in host {
        let t = h.prepared.time_gps_s;
        if t - t0 < ONSET_S {
            continue;
        }
        let x = h.prepared.reference_m.expect("a reference position");
        let rot = raim_core::frames::enu_rotation(&raim_core::frames::ecef_to_geodetic(x));
        let shift = raim_core::frames::unrotate(&rot, shift_enu_m);
        let mut sats: Vec<RangeObservation> = h.obs.clone();
        for (id, b) in
            raim_gnss::faults::constellation_bias(&mut sats, System::Galileo, x, 0.0, shift)
        {
            table.insert(((t - t0).round() as i64, id), b);
        }
    }
    table
}

/// Host side only (no QEMU): with an ISM in force every stream epoch of
/// the host `Server` is an ARAIM epoch whose answer body is the one the
/// host's own epochs get as `Araim(Ranges)` requests; clean, every epoch
/// has ARAIM service unless its detection test failed ([`check_clean`]);
/// the two faults are caught as the module docs say,
/// the constellation fault also as `raim rtcm-fault --araim-const-fault`
/// writes it.
///
/// Verifies: RX-ARAIM, RX-STREAM-FAULT
#[test]
fn host_server_stream_araim_is_the_araim_path() {
    let (bytes, host) = stream();
    let ism = ism(&host);
    println!("ISM: {} satellites", ism.0.len());
    let (answers, nmea) = host_run(&ism, &bytes);
    assert_eq!(answers.len(), EPOCHS);
    let direct = host_epoch_answers(&ism, &host);
    for (a, d) in answers.iter().zip(&direct) {
        assert_eq!(a.seq, None);
        assert_eq!(&a.body, d);
    }
    let clean = outcomes(&answers, &host);
    check_clean(&clean);
    let ok = clean.iter().filter(|o| o.1 == Decision::Ok).count();
    let modes: Vec<u32> = answers
        .iter()
        .map(|a| araim_result(&a.body).all_in_view.modes)
        .collect();
    let pls: Vec<(f64, f64)> = answers
        .iter()
        .map(|a| {
            let w = araim_result(&a.body).in_force();
            (w.vpl_m, w.hpl_m)
        })
        .collect();
    let mean = |f: fn(&(f64, f64)) -> f64| pls.iter().map(f).sum::<f64>() / pls.len() as f64;
    let max = |f: fn(&(f64, f64)) -> f64| pls.iter().map(f).fold(0.0, f64::max);
    println!(
        "clean: {ok} of {EPOCHS} Ok, modes {}..{}, VPL mean {:.2} m max {:.2} m, HPL mean {:.2} m max {:.2} m, {} NMEA lines",
        modes.iter().min().unwrap(),
        modes.iter().max().unwrap(),
        mean(|p| p.0),
        max(|p| p.0),
        mean(|p| p.1),
        max(|p| p.1),
        nmea.len()
    );

    let e = galileo_in_all(&host);
    let (answers, _) = host_run(&ism, &with_step(&bytes, e, 30.0));
    let step = outcomes(&answers, &host);
    check_step(&step, &clean, e);

    let (answers, _) = host_run(&ism, &with_galileo_shift(&bytes, &host, [0.0, 0.0, 60.0]));
    let shift = outcomes(&answers, &host);
    check_constellation(&shift, &clean, &host);

    // `raim rtcm-fault --araim-const-fault E:0:0,0,60@+600`'s biases
    // (`constellation_table`: the file read whole, the station's lines of
    // sight) against the ones above (the causal host epochs' reference
    // positions): within 1 mm for every satellite used; and its stream is
    // caught alike.
    let first = raim_recv::msm_fault::first_msm_gps_s(&bytes).unwrap();
    let lib = raim_recv::msm_fault::constellation_table(
        &bytes,
        &[raim_recv::msm_fault::ConstellationShift {
            system: System::Galileo,
            common_m: 0.0,
            shift_enu_m: [0.0, 0.0, 60.0],
            start_s: first + ONSET_S,
            end_s: None,
        }],
    )
    .unwrap();
    let mine = galileo_shift_table(&host, [0.0, 0.0, 60.0]);
    let mut worst_m = 0.0f64;
    for ((k, id), b) in &mine {
        let key = (raim_recv::msm_fault::time_key(first + *k as f64), *id);
        let got = lib.get(&key).unwrap_or_else(|| panic!("{key:?} missing"));
        worst_m = worst_m.max((got - b).abs());
    }
    println!(
        "constellation_table against the host epochs' biases: {} entries, worst {worst_m:.1e} m",
        mine.len()
    );
    assert!(worst_m <= 1e-3, "{worst_m}");
    let plan = raim_gnss::faults::FaultPlan::default();
    let tool = raim_recv::msm_fault::fault_stream_with(&bytes, &plan, &lib).unwrap();
    let (answers, _) = host_run(&ism, &tool.bytes);
    check_constellation(&outcomes(&answers, &host), &clean, &host);
}

/// The clean stream: every epoch has ARAIM service unless its detection
/// test failed (an alarm or an exclusion: the data do not fit the
/// nominal model there, as they do not in `raim replay --araim` on the
/// RINEX, docs/RECEIVERS.md "Against `raim replay --araim`"); never
/// unavailable for its geometry; and most epochs `Ok` (an exclusion or
/// alarm at more than one epoch in ten would be a broken path, not the
/// model's misfit: the replay has 5 detections in 80).
fn check_clean(o: &[(f64, Decision, Vec<SatId>)]) {
    for (t, d, ex) in o {
        match d {
            Decision::Ok => assert!(ex.is_empty(), "+{t} s"),
            Decision::Excluded => assert!(!ex.is_empty(), "+{t} s"),
            Decision::Alarm => {}
            other => panic!("+{t} s: the clean stream answered {other:?}"),
        }
    }
    let ok = o.iter().filter(|x| x.1 == Decision::Ok).count();
    assert!(10 * ok >= 9 * o.len(), "{o:?}");
}

/// Before the onset, the clean stream's outcomes (the fault is not there
/// yet); from it, never passed: an alarm, or `sat` excluded, alone where
/// the clean stream passed its detection test (where it did not, the
/// exclusion holds `sat` and may hold more).
fn check_step(
    o: &[(f64, Decision, Vec<SatId>)],
    clean: &[(f64, Decision, Vec<SatId>)],
    sat: SatId,
) {
    let (mut excluded, mut alarms) = (0, 0);
    for ((t, d, ex), c) in o.iter().zip(clean) {
        if *t < ONSET_S {
            assert_eq!((d, ex), (&c.1, &c.2), "+{t} s: before the onset");
        } else {
            match d {
                Decision::Excluded => {
                    if c.1 == Decision::Ok {
                        assert_eq!(ex.as_slice(), &[sat], "+{t} s");
                    } else {
                        assert!(ex.contains(&sat), "+{t} s: {ex:?}, clean {c:?}");
                    }
                    excluded += 1;
                }
                Decision::Alarm => alarms += 1,
                other => panic!("+{t} s: 30 m on {sat:?} answered {other:?}"),
            }
        }
    }
    let after = o.iter().filter(|x| x.0 >= ONSET_S).count();
    println!(
        "30 m on {sat:?} from +{ONSET_S} s: {excluded} excluded, {alarms} alarms of {after} epochs"
    );
    assert_eq!(excluded + alarms, after);
}

/// Before the onset, the clean stream's outcomes; from it no epoch
/// passed: every Galileo satellite excluded (and nothing else where the
/// clean stream passed its detection test: the constellation mode), with
/// service on the rest (`Excluded`) or without it (`Unavailable`: the
/// protection levels of G+C exceed the alert limits), or an alarm.
fn check_constellation(
    o: &[(f64, Decision, Vec<SatId>)],
    clean: &[(f64, Decision, Vec<SatId>)],
    host: &[HostEpoch],
) {
    let (mut excluded, mut unavailable, mut alarms) = (0, 0, 0);
    for (((t, d, ex), h), c) in o.iter().zip(host).zip(clean) {
        if *t < ONSET_S {
            assert_eq!((d, ex), (&c.1, &c.2), "+{t} s: before the onset");
            continue;
        }
        let galileo: BTreeSet<SatId> = h
            .obs
            .iter()
            .filter(|s| s.id.system == System::Galileo)
            .map(|s| s.id)
            .collect();
        let got: BTreeSet<SatId> = ex.iter().copied().collect();
        let ok_set = |got: &BTreeSet<SatId>| {
            if c.1 == Decision::Ok {
                *got == galileo
            } else {
                galileo.is_subset(got)
            }
        };
        match d {
            Decision::Excluded => {
                assert!(ok_set(&got), "+{t} s: {got:?}");
                excluded += 1;
            }
            Decision::Unavailable => {
                assert!(
                    ok_set(&got),
                    "+{t} s: unavailable without the exclusion: {got:?}"
                );
                unavailable += 1;
            }
            Decision::Alarm => alarms += 1,
            other => panic!("+{t} s: the Galileo fault answered {other:?}"),
        }
    }
    let after = o.iter().filter(|x| x.0 >= ONSET_S).count();
    println!("Galileo displaced from +{ONSET_S} s: constellation excluded {excluded} with service, {unavailable} without, alarms {alarms} of {after} epochs");
    assert_eq!(excluded + unavailable + alarms, after);
}

/// The unit fed the ISM and `bytes` against the host server fed the same:
/// every answer byte for byte, the NMEA sentences line for line, the
/// stack within the firmware's goal. Returns the outcomes.
fn unit_equals_host(
    ism: &(Vec<IsmSat>, [Option<f64>; 5]),
    bytes: &[u8],
    host: &[HostEpoch],
    what: &str,
) -> Vec<(f64, Decision, Vec<SatId>)> {
    let (want, want_nmea) = host_run(ism, bytes);
    assert_eq!(want.len(), EPOCHS);
    let (got, nmea, status) = unit_run(ism, bytes, EPOCHS, want_nmea.len());
    for (k, (g, w)) in got.iter().zip(&want).enumerate() {
        assert_eq!(
            response_bytes(g),
            response_bytes(w),
            "{what}: epoch {k}: unit {g:?}\nhost {w:?}"
        );
    }
    assert_eq!(nmea, want_nmea, "{what}: NMEA");
    assert_eq!(status.stream_epochs as usize, EPOCHS);
    println!(
        "{what}: {EPOCHS} ARAIM stream epochs answered as the host server's, {} NMEA lines alike; stack high water {} B, last stream epoch {} ticks, last ARAIM epoch {} ticks",
        nmea.len(),
        status.stack_high_water_bytes,
        status.last_stream_ticks,
        status.last_epoch_ticks
    );
    assert!(
        status.stack_high_water_bytes <= STACK_GOAL_BYTES,
        "{what}: stack high water {} B",
        status.stack_high_water_bytes
    );
    outcomes(&got, host)
}

/// Clean: every stream epoch is an ARAIM epoch, with service unless its
/// detection test failed ([`check_clean`]), the unit's answers and NMEA
/// those of the host server on the same frames, and (through it) those of
/// the host's own epochs sent as `Araim(Ranges)`.
///
/// Verifies: RX-ARAIM, SAFE-STACK
#[test]
fn qemu_rtcm_araim_clean_stream_equals_the_host() {
    let (bytes, host) = stream();
    let ism = ism(&host);
    let o = unit_equals_host(&ism, &bytes, &host, "ESBC G+E+C clean");
    check_clean(&o);
}

/// The host server's outcomes on the clean stream (the reference before
/// a fault's onset).
fn clean_outcomes(
    ism: &(Vec<IsmSat>, [Option<f64>; 5]),
    bytes: &[u8],
    host: &[HostEpoch],
) -> Vec<(f64, Decision, Vec<SatId>)> {
    let (answers, _) = host_run(ism, bytes);
    outcomes(&answers, host)
}

/// A 30 m step on one Galileo satellite from epoch 20 of 80: excluded (or
/// an alarm) at every epoch from the onset; before it, the clean stream's
/// outcomes.
///
/// Verifies: RX-ARAIM, RX-STREAM-FAULT
#[test]
fn qemu_rtcm_araim_galileo_step_is_excluded() {
    let (bytes, host) = stream();
    let ism = ism(&host);
    let e = galileo_in_all(&host);
    let clean = clean_outcomes(&ism, &bytes, &host);
    let o = unit_equals_host(&ism, &with_step(&bytes, e, 30.0), &host, "30 m step");
    check_step(&o, &clean, e);
}

/// The Galileo constellation displaced 60 m upwards from epoch 20: the
/// constellation fault mode excludes Galileo (or the epoch is an alarm)
/// at every epoch from the onset; before it, the clean stream's outcomes.
///
/// Verifies: RX-ARAIM, RX-STREAM-FAULT
#[test]
fn qemu_rtcm_araim_galileo_constellation_fault_is_caught() {
    let (bytes, host) = stream();
    let ism = ism(&host);
    let faulted = with_galileo_shift(&bytes, &host, [0.0, 0.0, 60.0]);
    let clean = clean_outcomes(&ism, &bytes, &host);
    let o = unit_equals_host(&ism, &faulted, &host, "Galileo constellation fault");
    check_constellation(&o, &clean, &host);
}

/// The cost of an ARAIM stream epoch on the unit (BENCHMARKS.md
/// "Firmware: receiver stream"), under `-icount shift=0` (a SysTick tick
/// is 40 guest instructions): for the ESBC stream up to epoch `k`, clean
/// and with the 30 m Galileo step, the forming of epoch `k`
/// (`Status.last_stream_ticks`) and its ARAIM run (`last_epoch_ticks`:
/// all in view, and the exclusion when faulted), with the epoch's
/// satellites and modes. Printed, not asserted (a benchmark).
#[test]
fn qemu_rtcm_araim_stream_epoch_cost() {
    let (bytes, host) = stream();
    let ism = ism(&host);
    let e = galileo_in_all(&host);
    let faulted = with_step(&bytes, e, 30.0);
    let elf = raim_qemu::firmware_elf_stream(Machine::Mps2An386).unwrap();
    // The epoch measured: the last of the stream, and the first faulted.
    let onset = host
        .iter()
        .position(|h| h.prepared.time_gps_s - host[0].prepared.time_gps_s >= ONSET_S)
        .unwrap();
    for (what, stream, k) in [
        ("clean, last epoch", &bytes, EPOCHS - 1),
        ("30 m Galileo step, first faulted epoch", &faulted, onset),
    ] {
        // The frames up to the one that closed epoch k.
        let end = rtcm_common::frames(stream)
            .get(host[k].frame)
            .map(|f| f.as_ptr() as usize - stream.as_ptr() as usize + f.len())
            .unwrap();
        let mut fw = QemuSession::start_with(
            &elf,
            &raim_qemu::Options {
                icount: true,
                ..raim_qemu::Options::default()
            },
        )
        .unwrap();
        fw.call(ism_command(&ism.0, ism.1)).unwrap();
        for chunk in stream[..end].chunks(4096) {
            fw.send_raw(chunk).unwrap();
        }
        let mut last = None;
        for _ in 0..=k {
            last = Some(fw.recv(STREAM_TIMEOUT).unwrap());
        }
        let s = fw.status().unwrap();
        let w = araim_result(&last.as_ref().unwrap().body).clone();
        println!(
            "ARAIM stream epoch ({what}): {} satellites, {} modes, {:?} {:?}; forming {} ticks = {} instructions; ARAIM {} ticks = {} instructions; stack high water {} B",
            host[k].obs.len(),
            w.all_in_view.modes,
            w.decision,
            w.fde,
            s.last_stream_ticks,
            40 * u64::from(s.last_stream_ticks),
            s.last_epoch_ticks,
            40 * u64::from(s.last_epoch_ticks),
            s.stack_high_water_bytes
        );
        assert!(s.last_epoch_ticks > 0);
    }
}
