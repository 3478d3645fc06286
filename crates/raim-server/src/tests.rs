//! The server's answers, frame by frame, on the host.
extern crate std;
use super::*;
use crate::answer::ResponseRef;
use raim_core::{FiRule, LinearObservation, RangeObservation, SatId, System};
use raim_proto::frame::encode;
use raim_proto::frame::FrameReceiver;
use raim_proto::message::{CommandRef, RequestRef, Response};
use serde::Serialize;
use std::vec::Vec;

/// The stack of a test thread that builds large engines by value. In the
/// debug profile a constructor passes its value through a chain of frames,
/// each `new`/`Default` holding its fields' temporaries: about three times
/// the engine's size, so a test that builds a few of them overflows the
/// 2 MiB default test thread. A constructor that builds in place (a
/// `const fn new` into a static) would need none of it.
pub(crate) const BIG_STACK_BYTES: usize = 32 << 20;

/// Runs `f` on a thread of [`BIG_STACK_BYTES`], passing its panic on.
pub(crate) fn on_big_stack<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    std::thread::scope(|s| {
        std::thread::Builder::new()
            .stack_size(BIG_STACK_BYTES)
            .spawn_scoped(s, f)
            .expect("spawning a test thread")
            .join()
            .unwrap_or_else(|e| std::panic::resume_unwind(e))
    })
}

/// A server that has taken the default configuration at run time.
/// On the heap: a debug build's moves of a server by value overflow a
/// test thread's 2 MiB stack.
fn bench() -> std::boxed::Box<Server> {
    let mut s = std::boxed::Box::new(Server::new());
    s.take_runtime_config(Config::default()).unwrap();
    s
}

/// A byte sink for the tests.
#[derive(Default)]
struct Sink(Vec<u8>);
impl embedded_io::ErrorType for Sink {
    type Error = core::convert::Infallible;
}
impl Write for Sink {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        self.0.extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
}

fn frame(req: &RequestRef<'_>) -> Vec<u8> {
    let mut scratch = [0u8; 4096];
    let mut out = [0u8; 4096];
    encode(req, &mut scratch, &mut out).unwrap().to_vec()
}

fn responses(bytes: &[u8]) -> Vec<Response> {
    let mut rx = FrameReceiver::<MAX_RESPONSE_FRAME>::new();
    bytes
        .iter()
        .filter_map(|&b| {
            rx.push(b)
                .map(|p| postcard::from_bytes::<Response>(p.unwrap()).unwrap())
        })
        .collect()
}

fn run(server: &mut Server, bytes: &[u8]) -> (Vec<Response>, std::string::String) {
    let (mut link, mut nmea) = (Sink::default(), Sink::default());
    for &b in bytes {
        server
            .on_byte(b, &mut link, &mut nmea, &mut NoPlatform)
            .unwrap();
    }
    (
        responses(&link.0),
        std::string::String::from_utf8(nmea.0).unwrap(),
    )
}

fn sky(step_m: f64) -> Vec<LinearObservation> {
    let sky = [
        (0.0, 85.0),
        (45.0, 30.0),
        (100.0, 50.0),
        (150.0, 20.0),
        (200.0, 60.0),
        (250.0, 25.0),
        (300.0, 40.0),
        (340.0, 15.0),
    ];
    sky.iter()
        .enumerate()
        .map(|(i, &(az, el)): (usize, &(f64, f64))| {
            let r = if i == 1 { step_m } else { 0.1 * i as f64 - 0.3 };
            let mut o = LinearObservation::from_az_el(
                SatId::new(System::Gps, i as u8 + 1),
                az.to_radians(),
                el.to_radians(),
                r,
            );
            o.sigma_m = Some(1.0);
            o
        })
        .collect()
}

/// Verifies: SPEC-11
#[test]
fn every_frame_is_answered_in_order_with_its_sequence_number() {
    let mut server = bench();
    let s0 = sky(0.0);
    let s1 = sky(50.0);
    let mut bytes = frame(&RequestRef::linear(0, 0.0, &s0));
    bytes.extend(frame(&RequestRef::linear(1, 1.0, &s1)));
    bytes.extend(frame(&RequestRef {
        seq: 2,
        command: CommandRef::Status,
    }));
    let (resp, nmea) = run(&mut server, &bytes);
    assert_eq!(resp.len(), 3);
    assert_eq!(
        resp.iter().map(|r| r.seq).collect::<Vec<_>>(),
        [Some(0), Some(1), Some(2)]
    );
    let ResponseBody::Result(r1) = &resp[1].body else {
        panic!("{:?}", resp[1])
    };
    assert_eq!(r1.exclusions[0].id, SatId::new(System::Gps, 2));
    // The same result as the core on the host, bit for bit.
    let direct = Raim::<CAPACITY, DevicePrecision>::new()
        .process(&Config::default(), &Epoch::linear(1.0, &s1))
        .unwrap();
    assert_eq!(*r1, WireResult::from_result(&direct));
    let ResponseBody::Status(st) = resp[2].body else {
        panic!()
    };
    assert_eq!(
        (st.frames, st.epochs, st.errors, st.capacity),
        (3, 2, 0, crate::SNAPSHOT_SATS as u16)
    );
    // Each solved epoch's sentences, from RMC to ZDA (GSV only in a build
    // with raim-proto's `nmea-sky`), twice.
    let kinds: Vec<&str> = nmea.lines().map(|l| &l[3..6]).collect();
    assert_eq!(kinds.iter().filter(|k| **k == "RMC").count(), 2);
    assert_eq!(kinds.first(), Some(&"RMC"));
    assert_eq!(kinds.last(), Some(&"ZDA"));
    // The host's writer on the same epoch, byte for byte.
    let want: std::string::String = raim_proto::nmea::epoch_sentences(
        r1,
        &raim_proto::nmea::Sky::new(&Epoch::linear(1.0, &s1)),
        raim_proto::nmea::BUILT,
    )
    .unwrap()
    .iter()
    .map(|s| s.as_str())
    .collect();
    assert!(nmea.ends_with(&want), "{nmea}");
}

/// Verifies: WIRE-BadCrc, WIRE-Undecodable, WIRE-Overflow, WIRE-SequenceGap, WIRE-TooManySatellites, WIRE-NonFinite, WIRE-DegenerateGeometry
#[test]
fn typed_errors_for_each_kind_of_bad_frame() {
    let mut server = bench();
    let good = sky(0.0);
    let mut nan = sky(0.0);
    nan[3].residual_m = f64::NAN;
    let many: Vec<LinearObservation> = (0..40)
        .map(|i| LinearObservation {
            id: SatId::new(System::Gps, i),
            ..good[0]
        })
        .collect();
    let degenerate: Vec<RangeObservation> = (0..6)
        .map(|i| RangeObservation {
            id: SatId::new(System::Gps, i + 1),
            pseudorange_m: 2.0e7,
            position_m: [2.0e7, 0.0, 0.0],
            sigma_m: Some(1.0),
        })
        .collect();
    let bad_cfg = Config {
        rule: FiRule::LraimGaussian { kappa: -1.0 },
        ..Config::default()
    };
    // A frame whose CRC does not match its payload.
    let mut payload = [0u8; 4096];
    let payload = postcard::to_slice(&RequestRef::linear(3, 0.0, &good), &mut payload).unwrap();
    let env = raim_proto::frame::Envelope {
        crc32: raim_proto::frame::CRC32.checksum(payload) ^ 1,
        payload,
    };
    let mut out = [0u8; 4096];
    let corrupted = postcard::to_slice_cobs(&env, &mut out).unwrap().to_vec();
    let mut bytes = Vec::new();
    bytes.extend(frame(&RequestRef::linear(0, 0.0, &nan)));
    bytes.extend(frame(&RequestRef::linear(1, 0.0, &many)));
    bytes.extend(frame(&RequestRef::ranges(2, 0.0, None, &degenerate)));
    bytes.extend(&corrupted);
    bytes.extend([0x01, 0x01, 0x00]); // valid COBS, not an envelope
    bytes.extend(frame(&RequestRef {
        seq: 5,
        command: CommandRef::Configure(&bad_cfg),
    }));
    bytes.extend(std::vec![0x11; MAX_REQUEST_FRAME + 5]);
    bytes.push(0);
    bytes.extend(frame(&RequestRef {
        seq: 6,
        command: CommandRef::Status,
    }));
    let (resp, nmea) = run(&mut server, &bytes);
    // Each of the three epochs writes its no-fix sentences (status void),
    // and so does each of the three frames that could not be read (CRC,
    // not an envelope, overflow: any of them may have been an epoch;
    // issue 35), with empty time and date fields.
    let rmc: Vec<&str> = nmea.lines().filter(|l| l.contains("RMC,")).collect();
    assert_eq!(rmc.len(), 6, "{nmea}");
    assert!(
        rmc.iter().all(|l| l.split(',').nth(2) == Some("V")),
        "{nmea}"
    );
    assert!(
        rmc[3..]
            .iter()
            .all(|l| l.split(',').nth(1) == Some("") && l.split(',').nth(9) == Some("")),
        "{nmea}"
    );
    let got: Vec<(Option<u32>, &str)> = resp
        .iter()
        .map(|r| {
            let ResponseBody::Error(e) = &r.body else {
                return (r.seq, "ok");
            };
            let kind = match e {
                WireError::NonFinite { .. } => "nonfinite",
                WireError::TooManySatellites {
                    have: 40,
                    capacity: 32,
                } => "toomany",
                WireError::DegenerateGeometry { .. } => "degenerate",
                WireError::BadCrc { .. } => "crc",
                WireError::Undecodable { .. } => "undecodable",
                WireError::SequenceGap {
                    expected: 3,
                    received: 5,
                } => "gap",
                WireError::OutOfRange { field, .. } if field.as_str() == "kappa" => "range",
                WireError::Overflow { .. } => "overflow",
                other => panic!("{other:?}"),
            };
            (r.seq, kind)
        })
        .collect();
    assert_eq!(
        got,
        [
            (Some(0), "nonfinite"),
            (Some(1), "toomany"),
            (Some(2), "degenerate"),
            (None, "crc"),
            (None, "undecodable"),
            (Some(5), "gap"),
            (Some(5), "range"),
            (None, "overflow"),
            (Some(6), "ok"),
        ]
    );
    // The bad configuration did not replace the good one.
    assert_eq!(server.config(), Some(&Config::default()));
    let ResponseBody::Status(st) = resp[8].body else {
        panic!()
    };
    assert_eq!((st.frames, st.errors), (8, 8));
}

/// The answers are encoded from references (`ResponseRef`);
/// the bytes are those of the owned `Response`, variant by variant.
#[test]
fn body_ref_encodes_as_response_body() {
    let direct = Raim::<CAPACITY, DevicePrecision>::new()
        .process(&Config::default(), &Epoch::linear(1.0, &sky(50.0)))
        .unwrap();
    let mut server = bench();
    let (st, _) = run(
        &mut server,
        &frame(&RequestRef {
            seq: 0,
            command: CommandRef::Status,
        }),
    );
    let ResponseBody::Status(status) = st[0].body else {
        panic!()
    };
    let bodies = [
        ResponseBody::Result(WireResult::from_result(&direct)),
        ResponseBody::Configured,
        ResponseBody::Status(status),
        ResponseBody::Error(WireError::SequenceGap {
            expected: 3,
            received: 5,
        }),
        ResponseBody::LockEngaged,
    ];
    fn enc<T: Serialize>(x: &T) -> Vec<u8> {
        let mut b = std::vec![0u8; MAX_RESPONSE_PAYLOAD];
        postcard::to_slice(x, &mut b).unwrap().to_vec()
    }
    for (i, body) in bodies.iter().enumerate() {
        let config = ConfigId {
            fingerprint: [0xDE; 16],
            locked: i % 2 == 0,
            source: raim_proto::ConfigSource::Runtime,
        };
        let seq = Some(i as u32);
        let owned = enc(&Response {
            seq,
            body: body.clone(),
            config,
        });
        let by_ref = enc(&ResponseRef {
            seq,
            body: BodyRef::from(body),
            config,
        });
        assert_eq!(owned, by_ref, "{body:?}");
    }
}

/// The epochs' cycles in `Status`: on a platform whose cycle counter
/// runs, the last and the largest span of each kind (across the counter's
/// wrap), "running, none yet" before the first epoch; on one without a
/// counter (the host's `NoPlatform`), `NotMeasured` after epochs too,
/// never a zero count.
///
/// Verifies: FW-CYCLES
#[test]
fn status_reports_epoch_cycles_when_the_counter_runs_and_not_measured_otherwise() {
    /// A cycle counter that advances by `step` at every read, from just
    /// below its wrap.
    struct Counting {
        cycles: u32,
        step: u32,
    }
    impl Platform for Counting {
        fn now(&mut self) -> u32 {
            0
        }
        fn cycles(&mut self) -> Option<u32> {
            let c = self.cycles;
            self.cycles = self.cycles.wrapping_add(self.step);
            Some(c)
        }
    }
    let status = |server: &mut Server, p: &mut Counting, seq: u32| -> Status {
        let (mut link, mut nmea) = (Sink::default(), Sink::default());
        for b in frame(&RequestRef {
            seq,
            command: CommandRef::Status,
        }) {
            server.on_byte(b, &mut link, &mut nmea, p).unwrap();
        }
        let resp = responses(&link.0);
        let ResponseBody::Status(st) = resp[0].body else {
            panic!("{:?}", resp[0])
        };
        st
    };
    let mut server = bench();
    let mut p = Counting {
        cycles: u32::MAX - 500,
        step: 0,
    };
    assert_eq!(
        status(&mut server, &mut p, 0).epoch_cycles,
        EpochCycles::RUNNING
    );
    let s0 = sky(0.0);
    for (step, seq) in [(3_000, 1), (1_000, 2)] {
        p.step = step;
        let (mut link, mut nmea) = (Sink::default(), Sink::default());
        for b in frame(&RequestRef::linear(seq, f64::from(seq), &s0)) {
            server.on_byte(b, &mut link, &mut nmea, &mut p).unwrap();
        }
        assert!(matches!(
            responses(&link.0)[0].body,
            ResponseBody::Result(_)
        ));
    }
    let st = status(&mut server, &mut p, 3);
    assert_eq!(
        st.epoch_cycles,
        EpochCycles::Measured {
            snapshot: Some(raim_proto::CycleSpan {
                last_cycles: 1_000,
                max_cycles: 3_000,
            }),
            araim: None,
            pf: None,
            stream_forming: None,
        }
    );
    // No counter: the same epochs leave it "not measured".
    let mut host = bench();
    let mut bytes = frame(&RequestRef::linear(1, 1.0, &s0));
    bytes.extend(frame(&RequestRef {
        seq: 2,
        command: CommandRef::Status,
    }));
    let (resp, _) = run(&mut host, &bytes);
    let ResponseBody::Status(st) = resp[1].body else {
        panic!("{:?}", resp[1])
    };
    assert_eq!(st.epochs, 1);
    assert_eq!(st.epoch_cycles, EpochCycles::NotMeasured);
}

/// `Status` carries the platform's reset count and cause; a
/// test fault on a platform without test hooks is refused, typed.
///
/// Verifies: SAFE-FAULT, WIRE-TestHooksDisabled
#[test]
fn status_reports_the_reset_record_and_test_hooks_are_off_by_default() {
    struct Rebooted;
    impl Platform for Rebooted {
        fn now(&mut self) -> u32 {
            0
        }
        fn reset_record(&mut self) -> (u32, ResetCause) {
            (3, ResetCause::Watchdog { pc: 0x1234 })
        }
    }
    let mut server = bench();
    let mut bytes = frame(&RequestRef {
        seq: 0,
        command: CommandRef::Status,
    });
    bytes.extend(frame(&RequestRef {
        seq: 1,
        command: CommandRef::TestFault(TestFault::Hang),
    }));
    let (mut link, mut nmea) = (Sink::default(), Sink::default());
    for &b in &bytes {
        server
            .on_byte(b, &mut link, &mut nmea, &mut Rebooted)
            .unwrap();
    }
    let resp = responses(&link.0);
    let ResponseBody::Status(st) = resp[0].body else {
        panic!("{:?}", resp[0])
    };
    assert_eq!(
        (st.resets, st.reset_cause),
        (3, ResetCause::Watchdog { pc: 0x1234 })
    );
    assert_eq!(
        resp[1].body,
        ResponseBody::Error(WireError::TestHooksDisabled)
    );
    // The host-test platform keeps no record: power-on.
    let (resp, _) = run(
        &mut bench(),
        &frame(&RequestRef {
            seq: 0,
            command: CommandRef::Status,
        }),
    );
    let ResponseBody::Status(st) = resp[0].body else {
        panic!()
    };
    assert_eq!((st.resets, st.reset_cause), (0, ResetCause::PowerOn));
}

/// The platform hears every epoch's verdict (typed errors as
/// `None`, too-many-satellites included) and fills its Status fields;
/// Status tells whether a key is provisioned.
#[test]
fn the_platform_hears_every_epoch_verdict_and_fills_status() {
    use raim_core::Decision;
    use raim_proto::alert::{AlarmOutput, AlertMonitor};
    struct Discrete(AlertMonitor, u64);
    impl Platform for Discrete {
        fn now(&mut self) -> u32 {
            0
        }
        fn on_epoch(&mut self, decision: Option<Decision>) {
            self.1 += 1;
            self.0.on_epoch(self.1, decision);
        }
        fn board_status(&mut self, status: &mut Status) {
            status.alarm_output = self.0.output(self.1);
            status.alarm_pin_asserted = status.alarm_output.asserted();
            status.rx_ring_overflows = 7;
        }
    }
    let (ok, fault) = (sky(0.0), sky(50.0));
    let mut nan = sky(0.0);
    nan[0].residual_m = f64::NAN;
    let many: Vec<LinearObservation> = (0..40)
        .map(|i| LinearObservation {
            id: SatId::new(System::Gps, i),
            ..ok[0]
        })
        .collect();
    let status = |seq| {
        frame(&RequestRef {
            seq,
            command: CommandRef::Status,
        })
    };
    let mut bytes = status(0);
    bytes.extend(frame(&RequestRef::linear(1, 0.0, &ok)));
    bytes.extend(status(2));
    bytes.extend(frame(&RequestRef::linear(3, 1.0, &nan)));
    bytes.extend(status(4));
    bytes.extend(frame(&RequestRef::linear(5, 2.0, &fault)));
    bytes.extend(status(6));
    bytes.extend(frame(&RequestRef::linear(7, 3.0, &many)));
    bytes.extend(status(8));
    let mut server = bench();
    let mut p = Discrete(AlertMonitor::new(100), 0);
    let (mut link, mut nmea) = (Sink::default(), Sink::default());
    for &b in &bytes {
        server.on_byte(b, &mut link, &mut nmea, &mut p).unwrap();
    }
    let outputs: Vec<(AlarmOutput, bool, u32, bool)> = responses(&link.0)
        .iter()
        .filter_map(|r| match r.body {
            ResponseBody::Status(s) => Some((
                s.alarm_output,
                s.alarm_pin_asserted,
                s.rx_ring_overflows,
                s.auth_provisioned,
            )),
            _ => None,
        })
        .collect();
    // The 50 m fault on one of 8 satellites is excluded: valid.
    assert_eq!(
        outputs,
        [
            (AlarmOutput::NoValidEpoch, true, 7, false),
            (AlarmOutput::Clear, false, 7, false),
            (AlarmOutput::EpochError, true, 7, false),
            (AlarmOutput::Clear, false, 7, false),
            (AlarmOutput::EpochError, true, 7, false),
        ]
    );
    assert_eq!(p.1, 4);
    let mut keyed = Server::with_auth_key([1; 32]);
    let (resp, _) = run(&mut keyed, &status(0));
    let ResponseBody::Status(st) = resp[0].body else {
        panic!()
    };
    assert!(st.auth_provisioned);
}

/// The written-out fingerprint of the unconfigured unit is the computed one.
#[test]
fn unconfigured_fingerprint_is_computed() {
    let computed = UnitConfigRef {
        snapshot: None,
        araim: None,
        pf: None,
        host_sigmas: true,
        model_check: &raim_proto::WireModelCheckConfig::DEFAULT,
    }
    .fingerprint();
    assert_eq!(crate::UNCONFIGURED_FINGERPRINT, computed);
    let server = std::boxed::Box::new(Server::new());
    assert_eq!(server.status().config.fingerprint, computed);
}

/// `Status.hardware_entropy` reports the source the boot was given, and a
/// server that never booted has had none; the nonce follows the bytes.
///
/// Verifies: SAFE-T10
#[test]
fn status_reports_whether_the_boot_nonce_had_hardware_entropy() {
    use raim_proto::auth::BootEntropy;
    let unbooted = std::boxed::Box::new(Server::new());
    assert!(!unbooted.status().hardware_entropy);
    let mut nonces = std::vec::Vec::new();
    for (bytes, hardware) in [([0; 32], false), ([0; 32], true), ([9; 32], true)] {
        let mut s = std::boxed::Box::new(Server::new());
        s.boot(Ok(None), 0, &BootEntropy { bytes, hardware });
        assert_eq!(s.status().hardware_entropy, hardware);
        assert_eq!(s.status().boot_nonce, s.nonce());
        nonces.push(s.nonce());
    }
    // The flag is reported, not hashed: the same bytes give the same nonce.
    assert_eq!(nonces[0], nonces[1]);
    assert_ne!(nonces[1], nonces[2]);
}

/// Issue 35 "Inputs", on the firmware's path: an epoch time outside the
/// GPS era (±1e300 s, NaN), PRN 0 and 255, and, with the MCUSUM on, a time
/// going backwards (t + 1, then t - 50) are each refused with a typed
/// error, the alarm output hears a refused epoch, and the no-fix sentences
/// go out; the MCUSUM epoch after them is answered as if they had never
/// come.
///
/// Verifies: SAFE-INPUTS, WIRE-PrnOutOfRange, WIRE-OutOfRange
#[test]
fn absurd_times_satellite_numbers_and_backward_time_are_refused() {
    let mut server = std::boxed::Box::new(Server::new());
    let on = Config::default().split_false_alarm_budget(raim_core::config::DEFAULT_SNAPSHOT_SHARE);
    server.take_runtime_config(on).unwrap();
    let mut twin = std::boxed::Box::new(Server::new());
    twin.take_runtime_config(on).unwrap();
    let good = sky(0.0);
    let mut prn0 = sky(0.0);
    prn0[2].id.prn = 0;
    let mut prn255 = sky(0.0);
    prn255[5].id.prn = 255;
    let t = 1_000.0;
    let mut bytes = Vec::new();
    let mut twin_bytes = Vec::new();
    for k in 0..5u32 {
        let f = frame(&RequestRef::linear(k, t - 4.0 + f64::from(k), &good));
        bytes.extend(&f);
        twin_bytes.extend(f);
    }
    // The refused ones (the twin never sees them), then t + 1 in order.
    let refused = [
        (1e300, &good),
        (-1e300, &good),
        (f64::NAN, &good),
        (t - 50.0, &good),
        (t, &good),
        (t + 0.5, &prn0),
        (t + 0.5, &prn255),
    ];
    for (i, (time_s, sats)) in refused.iter().enumerate() {
        bytes.extend(frame(&RequestRef::linear(5 + i as u32, *time_s, sats)));
    }
    bytes.extend(frame(&RequestRef::linear(12, t + 1.0, &good)));
    twin_bytes.extend(frame(&RequestRef::linear(5, t + 1.0, &good)));
    struct Count(Vec<Option<raim_core::Decision>>);
    impl Platform for Count {
        fn now(&mut self) -> u32 {
            0
        }
        fn on_epoch(&mut self, d: Option<raim_core::Decision>) {
            self.0.push(d);
        }
    }
    let (mut link, mut nmea, mut p) = (Sink::default(), Sink::default(), Count(Vec::new()));
    for &b in &bytes {
        server.on_byte(b, &mut link, &mut nmea, &mut p).unwrap();
    }
    let resp = responses(&link.0);
    assert_eq!(resp.len(), 13, "{resp:?}");
    let era = raim_core::measurement::EPOCH_TIME_S;
    let oor = |value: f64| WireError::OutOfRange {
        field: raim_proto::error::field_name("time_s"),
        value,
        min: era.min,
        max: era.max,
    };
    let want = [
        oor(1e300),
        oor(-1e300),
        WireError::NonFinite {
            field: raim_proto::error::field_name("time_s"),
            index: 0,
            value: f64::NAN,
        },
        WireError::TimeNotIncreasing {
            previous_s: t,
            now_s: t - 50.0,
        },
        WireError::TimeNotIncreasing {
            previous_s: t,
            now_s: t,
        },
        WireError::PrnOutOfRange {
            index: 2,
            id: SatId::new(System::Gps, 0),
            max: 32,
        },
        WireError::PrnOutOfRange {
            index: 5,
            id: SatId::new(System::Gps, 255),
            max: 32,
        },
    ];
    for (k, w) in want.iter().enumerate() {
        let ResponseBody::Error(e) = &resp[5 + k].body else {
            panic!("{k}: {:?}", resp[5 + k])
        };
        // NaN != NaN: compare the encoded bytes.
        let (mut a, mut b) = ([0u8; 128], [0u8; 128]);
        assert_eq!(
            postcard::to_slice(e, &mut a).unwrap(),
            postcard::to_slice(w, &mut b).unwrap(),
            "{k}: {e:?}"
        );
    }
    // Every refused epoch reached the alarm output as a refusal.
    assert_eq!(p.0.len(), 13);
    assert!(p.0[5..12].iter().all(Option::is_none), "{:?}", p.0);
    // 13 epochs, 13 RMC sentences; the 7 refused ones void.
    let rmc: Vec<&str> = std::str::from_utf8(&nmea.0)
        .unwrap()
        .lines()
        .filter(|l| l.contains("RMC,"))
        .collect();
    assert_eq!(rmc.len(), 13);
    assert!(rmc[5..12].iter().all(|l| l.split(',').nth(2) == Some("V")));
    // The epoch after them: as the twin's, which never saw them.
    let (twin_resp, _) = run(&mut twin, &twin_bytes);
    let (ResponseBody::Result(a), ResponseBody::Result(b)) = (&resp[12].body, &twin_resp[5].body)
    else {
        panic!("{:?} {:?}", resp[12], twin_resp[5])
    };
    assert_eq!(a.mcusum, b.mcusum);
    assert_eq!(a.decision, b.decision);
}

/// Issue 35: a frame the unit cannot read may have been an epoch. A
/// 64-satellite Linear frame (longer than the receive buffer: `Overflow`),
/// a chunk that is not an envelope (`Undecodable`) and a frame with a bad
/// CRC each assert the alarm output at once (`EpochError`, as a refused
/// epoch) and write the no-fix sentences; the next valid epoch clears it.
/// A frame that is read and is not an epoch (`Status`) changes nothing.
///
/// Verifies: SAFE-UNREADABLE, SAFE-ALARM, WIRE-Overflow, WIRE-Undecodable, WIRE-BadCrc
#[test]
fn unreadable_frames_assert_the_alarm_at_once_and_write_no_fix() {
    use raim_proto::alert::{AlarmOutput, AlertMonitor};
    struct Discrete(AlertMonitor, u64);
    impl Platform for Discrete {
        fn now(&mut self) -> u32 {
            0
        }
        fn on_epoch(&mut self, decision: Option<raim_core::Decision>) {
            self.1 += 1;
            self.0.on_epoch(self.1, decision);
        }
        fn board_status(&mut self, status: &mut Status) {
            status.alarm_output = self.0.output(self.1);
            status.alarm_pin_asserted = status.alarm_output.asserted();
        }
    }
    let ok = sky(0.0);
    let big: Vec<LinearObservation> = (0..64u8)
        .map(|i| LinearObservation {
            id: SatId::new(System::Beidou, i % 63 + 1),
            ..ok[0]
        })
        .collect();
    let oversized = frame(&RequestRef::linear(2, 1.0, &big));
    assert!(oversized.len() > MAX_REQUEST_FRAME);
    let mut bad_crc = frame(&RequestRef::linear(7, 3.0, &ok));
    bad_crc[5] ^= 0x40;
    let mut server = bench();
    let mut p = Discrete(AlertMonitor::new(100), 0);
    let status = |seq| {
        frame(&RequestRef {
            seq,
            command: CommandRef::Status,
        })
    };
    let mut alarms = Vec::new();
    let mut rmc_count = Vec::new();
    let steps: [Vec<u8>; 7] = [
        frame(&RequestRef::linear(0, 0.0, &ok)),
        status(1),
        oversized,
        frame(&RequestRef::linear(4, 2.0, &ok)),
        std::vec![0x01, 0x01, 0x00],
        frame(&RequestRef::linear(6, 2.5, &ok)),
        bad_crc,
    ];
    for step in steps {
        let (mut link, mut nmea) = (Sink::default(), Sink::default());
        for &b in step.iter().chain(status(99).iter()) {
            server.on_byte(b, &mut link, &mut nmea, &mut p).unwrap();
        }
        let st = responses(&link.0)
            .into_iter()
            .find_map(|r| match r.body {
                ResponseBody::Status(s) => Some(s),
                _ => None,
            })
            .unwrap();
        alarms.push((st.alarm_output, st.alarm_pin_asserted));
        let nmea = std::string::String::from_utf8(nmea.0).unwrap();
        rmc_count.push(
            nmea.lines()
                .filter(|l| {
                    let f: Vec<&str> = l.split(',').collect();
                    l.contains("RMC,") && f[1].is_empty() && f[2] == "V"
                })
                .count(),
        );
    }
    assert_eq!(
        alarms,
        [
            (AlarmOutput::Clear, false),
            (AlarmOutput::Clear, false),
            (AlarmOutput::EpochError, true),
            (AlarmOutput::Clear, false),
            (AlarmOutput::EpochError, true),
            (AlarmOutput::Clear, false),
            (AlarmOutput::EpochError, true),
        ]
    );
    // A void RMC without a time for each unreadable frame (its time is
    // unknown), none for the others (linearised epochs: void, timed).
    assert_eq!(rmc_count, [0, 0, 1, 0, 1, 0, 1]);
}

/// The model check through the server (docs/MODEL_CHECK.md): an 8-satellite
/// sky whose residuals pass the snapshot test (`Ok`) but are several times
/// the sigma model's, sent every 1,800 s, is declared broken within the
/// window: from then on the same epoch is answered `Unavailable`, and
/// `Status.model_check` says when; a new `Configure` puts a new model in
/// force and the check starts again (`Ok`). The nominal sky never breaks
/// it.
///
/// Verifies: SAFE-MODEL
#[test]
fn a_model_the_residuals_deny_makes_the_unit_unavailable_until_reconfigured() {
    let spacing_s = raim_core::consistency::DEFAULT_SPACING_S;
    use raim_core::consistency::DEFAULT_WINDOW;
    use raim_core::{Decision, Epoch, Raim};
    let cfg = Config::default();
    // The largest scale of a fixed residual pattern that the snapshot test
    // still passes, found with the core itself (the server's engine).
    let pattern = [1.0, -1.2, 0.8, -0.6, 1.1, -0.9, 0.7, -1.3];
    let scaled = |a: f64| -> Vec<LinearObservation> {
        sky(0.0)
            .into_iter()
            .zip(pattern)
            .map(|(mut o, p)| {
                o.residual_m = a * p;
                o
            })
            .collect()
    };
    let mut core =
        std::boxed::Box::new(Raim::<{ raim_proto::CAPACITY }, raim_proto::DevicePrecision>::new());
    let mut best = None;
    for k in 1..200 {
        let a = 0.1 * f64::from(k);
        let r = core.process(&cfg, &Epoch::linear(0.0, &scaled(a))).unwrap();
        match (r.decision, r.model_sample()) {
            (Decision::Ok, Some((q, dof))) => best = Some((a, q, dof)),
            _ => break,
        }
    }
    let (a, q, dof) = best.expect("an Ok scale");
    assert!(q / f64::from(dof) > 3.0, "q {q}, dof {dof}");
    let (loud, calm) = (scaled(a), scaled(0.05));

    let status = |seq| {
        frame(&RequestRef {
            seq,
            command: CommandRef::Status,
        })
    };
    let decision = |r: &Response| match &r.body {
        ResponseBody::Result(w) => w.decision,
        other => panic!("{other:?}"),
    };
    on_big_stack(|| {
        let mut server = bench();
        // The nominal sky: no declaration over twice the window.
        let mut t = 1.0e9;
        let mut seq = 0;
        for _ in 0..(2 * DEFAULT_WINDOW) {
            t += spacing_s;
            seq += 1;
            let (r, _) = run(&mut server, &frame(&RequestRef::linear(seq, t, &calm)));
            assert_eq!(decision(&r[0]), Decision::Ok);
        }
        // The loud sky: Ok until the window rejects, then Unavailable.
        let mut declared = None;
        for k in 1..=DEFAULT_WINDOW {
            t += spacing_s;
            seq += 1;
            let (r, _) = run(&mut server, &frame(&RequestRef::linear(seq, t, &loud)));
            if decision(&r[0]) == Decision::Unavailable {
                declared = Some((k, t));
                break;
            }
            assert_eq!(decision(&r[0]), Decision::Ok);
        }
        let (k, t_broken) = declared.expect("declared within the window");
        let (r, _) = run(&mut server, &status(seq + 1));
        let ResponseBody::Status(st) = r[0].body else {
            panic!("{r:?}")
        };
        assert_eq!(
            st.model_check.broken_at_ms,
            Some((t_broken * 1000.0) as u64)
        );
        assert!(st.model_check.rejections >= 1);
        // Latched: the calm sky too is Unavailable now.
        let (r, _) = run(
            &mut server,
            &frame(&RequestRef::linear(seq + 2, t + 1.0, &calm)),
        );
        assert_eq!(decision(&r[0]), Decision::Unavailable);
        // A new configuration: a new model in force, the check restarted.
        let (r, _) = run(
            &mut server,
            &frame(&RequestRef {
                seq: seq + 3,
                command: CommandRef::Configure(&cfg),
            }),
        );
        assert_eq!(r[0].body, ResponseBody::Configured);
        let (r, _) = run(
            &mut server,
            &frame(&RequestRef::linear(seq + 4, t + 2.0, &calm)),
        );
        assert_eq!(decision(&r[0]), Decision::Ok);
        let (r, _) = run(&mut server, &status(seq + 5));
        let ResponseBody::Status(st) = r[0].body else {
            panic!("{r:?}")
        };
        assert_eq!(st.model_check.broken_at_ms, None);
        std::println!(
            "scale {a:.1} (q {q:.1} at {dof} dof): declared at sample {k}, 1,800 s apart"
        );
    });
}

/// P(chi2(dof) > x) for an even `dof`, in closed form: the Poisson sum
/// e^(-x/2) sum_{i < dof/2} (x/2)^i / i!, independent of the core's
/// incomplete gamma (`stats::dist::gamma_q`).
fn chi2_sf_even_dof(dof: u32, x: f64) -> f64 {
    assert_eq!(dof % 2, 0);
    let h = x / 2.0;
    let mut term = (-h).exp();
    let mut sum = 0.0;
    for i in 0..dof / 2 {
        if i > 0 {
            term *= h / f64::from(i);
        }
        sum += term;
    }
    sum
}

/// The model check as docs/MODEL_CHECK.md writes it, for a constant
/// sample (q, dof) offered every `step_s`: samples at least `spacing_s`
/// apart, the last `window` of them, p = P(chi2(sum dof) > sum q) against
/// p_eval = P_h / (floor(3600 / spacing_s) + 1); the index (from 1) of the
/// first offer whose window rejects, if any within `offers`.
fn predicted_declaration(
    c: &raim_proto::WireModelCheckConfig,
    (q, dof): (f64, u32),
    step_s: f64,
    offers: usize,
) -> Option<usize> {
    let p_eval = c.p_fa_per_hour / ((3600.0 / c.spacing_s).floor() + 1.0);
    let mut last: Option<f64> = None;
    let mut samples = 0u32;
    for k in 1..=offers {
        let t = step_s * k as f64;
        if last.is_some_and(|l| t - l < c.spacing_s) {
            continue;
        }
        last = Some(t);
        samples += 1;
        let n = samples.min(c.window);
        if chi2_sf_even_dof(n * dof, f64::from(n) * q) < p_eval {
            return Some(k);
        }
    }
    None
}

/// Issue 35: the model check runs with the settings of the unit
/// configuration, taken by `ModelCheck`. One 8-satellite sky whose
/// residuals the snapshot test passes, but at a few times the sigma
/// model's q, is sent every 900 s to units configured with the defaults,
/// with a window of 4, with a spacing of 900 s and with P_h 1e-3; each
/// declares the model broken at the epoch the check's own arithmetic
/// (`predicted_declaration`, with a closed-form chi-square independent of
/// the core's) gives for its settings, and those epochs differ from the
/// defaults' for each setting changed, so a setting that was not in force
/// would show. A nominal sky is declared under none of them. The
/// fingerprint covers the settings.
///
/// Verifies: MODEL-CONFIG, SAFE-MODEL
#[test]
fn the_model_check_runs_with_the_configured_settings() {
    use raim_core::{Decision, Epoch, Raim};
    use raim_proto::WireModelCheckConfig;
    const STEP_S: f64 = 900.0;
    const OFFERS: usize = 24;
    let cfg = Config::default();
    let d = WireModelCheckConfig::DEFAULT;
    let settings = [
        d,
        WireModelCheckConfig { window: 4, ..d },
        WireModelCheckConfig {
            spacing_s: 900.0,
            ..d
        },
        WireModelCheckConfig {
            p_fa_per_hour: 1e-3,
            ..d
        },
    ];
    let pattern = [1.0, -1.2, 0.8, -0.6, 1.1, -0.9, 0.7, -1.3];
    let scaled = |a: f64| -> Vec<LinearObservation> {
        sky(0.0)
            .into_iter()
            .zip(pattern)
            .map(|(mut o, p)| {
                o.residual_m = a * p;
                o
            })
            .collect()
    };
    // The sample of a scale, from the server's own engine; the first scale
    // the snapshot test passes (`Ok`) at which every changed setting
    // declares at another epoch than the defaults.
    let mut core =
        std::boxed::Box::new(Raim::<{ raim_proto::CAPACITY }, raim_proto::DevicePrecision>::new());
    let mut sample = |a: f64| {
        let r = core.process(&cfg, &Epoch::linear(0.0, &scaled(a))).unwrap();
        (r.decision == Decision::Ok)
            .then(|| r.model_sample())
            .flatten()
    };
    let (a, q, want) = (1..400)
        .map(|k| 0.01 * f64::from(k))
        .map_while(|a| sample(a).map(|s| (a, s)))
        .map(|(a, s)| {
            let want: Vec<_> = settings
                .iter()
                .map(|c| predicted_declaration(c, s, STEP_S, OFFERS))
                .collect();
            (a, s, want)
        })
        .find(|(_, _, w)| w[1..].iter().all(|x| *x != w[0]))
        .expect("a scale at which every setting changes the declaration");
    let calm = sample(0.05).unwrap();
    for c in &settings {
        assert_eq!(predicted_declaration(c, calm, STEP_S, OFFERS), None);
    }
    let (loud, quiet) = (scaled(a), scaled(0.05));
    on_big_stack(|| {
        let mut fingerprints = Vec::new();
        for (c, want) in settings.iter().zip(&want) {
            for (obs, want) in [(&loud, *want), (&quiet, None)] {
                let mut server = bench();
                let (r, _) = run(
                    &mut server,
                    &frame(&RequestRef {
                        seq: 1,
                        command: CommandRef::ModelCheck(*c),
                    }),
                );
                assert_eq!(r[0].body, ResponseBody::Configured);
                let fingerprint = r[0].config.fingerprint;
                let mut declared = None;
                for k in 1..=OFFERS {
                    let t = 1.0e9 + STEP_S * k as f64;
                    let (r, _) = run(
                        &mut server,
                        &frame(&RequestRef::linear(k as u32 + 1, t, obs)),
                    );
                    let ResponseBody::Result(w) = &r[0].body else {
                        panic!("{r:?}")
                    };
                    if w.decision == Decision::Unavailable {
                        declared = Some(k);
                        break;
                    }
                    assert_eq!(w.decision, Decision::Ok);
                }
                assert_eq!(declared, want, "{c:?}, q {q:?}");
                fingerprints.push(fingerprint);
            }
        }
        // One fingerprint per setting, the same for both skies.
        fingerprints.dedup();
        assert_eq!(fingerprints.len(), settings.len());
    });
    std::println!("scale {a:.2} m, sample {q:?}: declared at offers {want:?}");
}

/// Out-of-bounds model-check settings are refused with the field and the
/// value, plain or authenticated, and the settings in force stay (the
/// fingerprint, and the check at those settings); a provisioned unit
/// takes its settings (the fingerprint) and refuses any other.
///
/// Verifies: MODEL-CONFIG
#[test]
fn out_of_bounds_model_check_settings_are_refused_and_change_nothing() {
    use raim_proto::auth::{tag, Authenticated, Change};
    use raim_proto::WireModelCheckConfig;
    on_big_stack(|| {
        let d = WireModelCheckConfig::DEFAULT;
        let mut server = bench();
        let before = server.fingerprint();
        for bad in [
            WireModelCheckConfig { window: 0, ..d },
            WireModelCheckConfig { window: 17, ..d },
            WireModelCheckConfig {
                spacing_s: -1.0,
                ..d
            },
            WireModelCheckConfig {
                p_fa_per_hour: 1e-13,
                ..d
            },
        ] {
            assert_eq!(
                server.change_plain(&Change::ModelCheck(bad)),
                Err(bad.check().unwrap_err())
            );
            assert_eq!(server.fingerprint(), before);
            assert_eq!(*server.model.settings(), d);
        }
        let key = [5u8; 32];
        let mut keyed = std::boxed::Box::new(Server::with_auth_key(key));
        let w4 = WireModelCheckConfig { window: 4, ..d };
        let change = Change::ModelCheck(w4);
        assert_eq!(
            keyed.change_plain(&change),
            Err(raim_proto::WireError::AuthRequired)
        );
        let a = Authenticated {
            counter: 1,
            tag: tag(&key, &keyed.nonce(), 1, &change),
            change,
        };
        assert!(keyed.change_authenticated(&a).is_ok());
        assert_eq!(*keyed.model.settings(), w4);
        assert_eq!(keyed.model.config().window, 4);

        let unit = raim_proto::UnitConfig {
            snapshot: Some(Config::default()),
            araim: None,
            pf: None,
            host_sigmas: false,
            model_check: WireModelCheckConfig {
                spacing_s: 60.0,
                window: 16,
                p_fa_per_hour: 0.5,
            },
        };
        let mut installed = std::boxed::Box::new(Server::new());
        installed.provision(unit.clone()).unwrap();
        assert_eq!(installed.fingerprint(), unit.fingerprint());
        assert_eq!(installed.model.config().spacing_s, 60.0);
        assert_eq!(
            installed.change_plain(&Change::ModelCheck(d)),
            Err(raim_proto::WireError::Locked {
                fingerprint: unit.fingerprint()
            })
        );
        let mut bad_unit = unit;
        bad_unit.model_check.p_fa_per_hour = f64::NAN;
        let mut refused = std::boxed::Box::new(Server::new());
        assert_eq!(
            refused.provision(bad_unit),
            Err(raim_proto::unit::ProvisionError::InvalidPart(
                raim_proto::unit::UnitPart::ModelCheck
            ))
        );
        assert_eq!(refused.config, None);
    });
}

/// The boot counter's flash, in RAM: `Some` words work as NOR flash (a
/// program clears bits); `None` is a flash that takes no write at all
/// (QEMU's netduinoplus2: read-only memory, its controller ignoring every
/// command), reading zeros as that memory does where no image was loaded.
struct RamFlash(Option<[std::vec::Vec<u32>; 2]>);

impl raim_proto::boot_counter::CounterFlash for RamFlash {
    fn page_words(&self) -> usize {
        8
    }
    fn read(
        &mut self,
        page: usize,
        word: usize,
    ) -> Result<u32, raim_proto::boot_counter::FlashFault> {
        Ok(match &self.0 {
            Some(p) => p[page][word],
            None => 0,
        })
    }
    fn erase(&mut self, page: usize) -> Result<(), raim_proto::boot_counter::FlashFault> {
        if let Some(p) = &mut self.0 {
            p[page].fill(u32::MAX);
        }
        Ok(())
    }
    fn program(
        &mut self,
        page: usize,
        word: usize,
        value: u32,
    ) -> Result<(), raim_proto::boot_counter::FlashFault> {
        if let Some(p) = &mut self.0 {
            p[page][word] &= value;
        }
        Ok(())
    }
}

/// One power-on of a keyed unit: the counter advanced on `flash`, the
/// same entropy every time (QEMU under `-icount`: zeroed SRAM, no RNG).
fn power_on(flash: &mut RamFlash) -> std::boxed::Box<Server> {
    use raim_proto::boot_counter::{advance, BootCounterStatus};
    let mut s = std::boxed::Box::new(Server::with_auth_key([7; 32]));
    s.set_boot_counter(match advance(flash) {
        Ok(n) => BootCounterStatus::Count(n),
        Err(e) => BootCounterStatus::Failed(e),
    });
    s.boot(
        Ok(None),
        0,
        &raim_proto::auth::BootEntropy {
            bytes: [5; 32],
            hardware: false,
        },
    );
    s
}

/// An authenticated `Configure` (a weak one: Pfa 1e-2) and `Lock` under
/// `server`'s nonce, as frames.
fn configure_and_lock(server: &Server) -> Vec<u8> {
    use raim_proto::auth::{tag, AuthenticatedRef, ChangeRef};
    let weak = Config {
        pfa: 1e-2,
        ..Config::default()
    };
    let mut bytes = Vec::new();
    for (seq, change) in [(0, ChangeRef::Configure(&weak)), (1, ChangeRef::Lock)] {
        let counter = u64::from(seq) + 1;
        let a = AuthenticatedRef {
            counter,
            change,
            tag: tag(&[7; 32], &server.nonce(), counter, &change),
        };
        bytes.extend(frame(&RequestRef {
            seq,
            command: CommandRef::Authenticated(a),
        }));
    }
    bytes
}

/// Issue 35, replay across a power cycle: an authenticated `Configure` and
/// `Lock` recorded in one power-on, replayed in the next with the same
/// reset count and the same entropy, are refused `BadAuthTag`, since the
/// boot counter went into the nonce; the unit stays Unconfigured and
/// answers its epochs `Unconfigured`. Without a counter the two power-ons
/// had one nonce.
///
/// Verifies: SAFE-BOOT-COUNTER, WIRE-BadAuthTag
#[test]
fn a_frame_recorded_before_a_power_cycle_does_not_verify_after_it() {
    on_big_stack(|| {
        let mut flash = RamFlash(Some([std::vec![u32::MAX; 8], std::vec![u32::MAX; 8]]));
        let mut first = power_on(&mut flash);
        assert_eq!(
            first.status().boot_counter,
            raim_proto::boot_counter::BootCounterStatus::Count(1)
        );
        let recorded = configure_and_lock(&first);
        let (answers, _) = run(&mut first, &recorded);
        assert_eq!(answers[0].body, ResponseBody::Configured);
        assert_eq!(answers[1].body, ResponseBody::LockEngaged);

        let mut second = power_on(&mut flash);
        assert_eq!(
            second.status().boot_counter,
            raim_proto::boot_counter::BootCounterStatus::Count(2)
        );
        assert_ne!(second.nonce(), first.nonce());
        let (answers, _) = run(&mut second, &recorded);
        for (a, counter) in answers.iter().zip([1, 2]) {
            assert_eq!(
                a.body,
                ResponseBody::Error(WireError::BadAuthTag { counter })
            );
        }
        assert_eq!(second.config_id().source, ConfigSource::Unconfigured);
        assert!(!second.config_id().locked);
        let sats = sky(0.0);
        let (answers, _) = run(&mut second, &frame(&RequestRef::linear(2, 0.0, &sats)));
        assert!(matches!(
            answers[0].body,
            ResponseBody::Error(WireError::Unconfigured { provision: None })
        ));

        // The same two power-ons without a counter: one nonce.
        let absent = |s: &mut Server| {
            s.boot(
                Ok(None),
                0,
                &raim_proto::auth::BootEntropy {
                    bytes: [5; 32],
                    hardware: false,
                },
            );
            s.nonce()
        };
        let mut a = std::boxed::Box::new(Server::with_auth_key([7; 32]));
        let mut b = std::boxed::Box::new(Server::with_auth_key([7; 32]));
        assert_eq!(absent(&mut a), absent(&mut b));
    })
}

/// Issue 35, "make a failed write fail safe": a counter the flash does not
/// take (it does not read back) leaves the boot without a count; `Status`
/// says why, every authenticated change is refused with the typed
/// `BootCounter` (never taken under a nonce that may have been used
/// before), the unit stays Unconfigured and answers its epochs
/// `Unconfigured` (the alarm output asserted).
///
/// Verifies: SAFE-BOOT-COUNTER, WIRE-BootCounter
#[test]
fn a_failed_boot_counter_takes_no_authenticated_change() {
    on_big_stack(|| {
        use raim_proto::boot_counter::{BootCounterError, BootCounterStatus};
        let mut flash = RamFlash(None);
        let mut unit = power_on(&mut flash);
        let error = BootCounterError::EraseVerify {
            page: 0,
            word: 0,
            value: 0,
        };
        assert_eq!(unit.status().boot_counter, BootCounterStatus::Failed(error));
        let frames = configure_and_lock(&unit);
        let (answers, _) = run(&mut unit, &frames);
        assert_eq!(answers.len(), 2);
        for a in &answers {
            assert_eq!(
                a.body,
                ResponseBody::Error(WireError::BootCounter { error })
            );
        }
        assert_eq!(unit.config_id().source, ConfigSource::Unconfigured);
        assert_eq!(unit.config(), None);
        let sats = sky(0.0);
        let (answers, nmea) = run(&mut unit, &frame(&RequestRef::linear(2, 0.0, &sats)));
        assert!(matches!(
            answers[0].body,
            ResponseBody::Error(WireError::Unconfigured { provision: None })
        ));
        // The no-fix sentences of a refused epoch.
        assert!(nmea.contains("$GPGGA") || nmea.contains("GGA"));
    })
}

/// The STM32F4's build with the stream (`ram-192k` and `rtcm`): the
/// snapshot monitor takes 24 satellites (`SNAPSHOT_SATS`), as ARAIM there.
/// A 24-satellite epoch is solved as the host's 32-satellite engine
/// solves it, a 25th satellite is the typed
/// `TooManySatellites { have: 25, capacity: 24 }`, never truncated, and
/// `Status` says 24. Run by scripts/test.sh with those features.
///
/// Verifies: WIRE-TooManySatellites
#[cfg(all(feature = "ram-192k", feature = "rtcm"))]
#[test]
fn the_stm32f4_stream_build_takes_24_satellites_and_refuses_the_25th_typed() {
    on_big_stack(|| {
        let mut server = bench();
        let sats = |n: u8| -> Vec<LinearObservation> {
            (0..n)
                .map(|i| {
                    let az = f64::from(i) * 137.5;
                    let el = 15.0 + f64::from(i % 7) * 10.0;
                    let mut o = LinearObservation::from_az_el(
                        SatId::new(System::Gps, i + 1),
                        az.to_radians(),
                        el.to_radians(),
                        0.05 * f64::from(i % 5) - 0.1,
                    );
                    o.sigma_m = Some(1.0);
                    o
                })
                .collect()
        };
        let (s24, s25) = (sats(24), sats(25));
        let mut bytes = Vec::new();
        bytes.extend(frame(&RequestRef::linear(0, 1.0, &s24)));
        bytes.extend(frame(&RequestRef::linear(1, 2.0, &s25)));
        bytes.extend(frame(&RequestRef {
            seq: 2,
            command: CommandRef::Status,
        }));
        let (resp, _) = run(&mut server, &bytes);
        assert_eq!(SNAPSHOT_SATS, 24);
        let ResponseBody::Result(r24) = &resp[0].body else {
            panic!("{:?}", resp[0].body)
        };
        let direct = Raim::<CAPACITY, DevicePrecision>::new()
            .process(&Config::default(), &Epoch::linear(1.0, &s24))
            .unwrap();
        assert_eq!(*r24, WireResult::from_result(&direct));
        assert_eq!(
            resp[1].body,
            ResponseBody::Error(WireError::TooManySatellites {
                have: 25,
                capacity: 24
            })
        );
        let ResponseBody::Status(st) = &resp[2].body else {
            panic!("{:?}", resp[2].body)
        };
        assert_eq!(st.capacity, 24);
    });
}
