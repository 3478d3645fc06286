//! The server's answers, frame by frame, on the host.
extern crate std;
use super::*;
use crate::answer::ResponseRef;
use raim_core::{FiRule, LinearObservation, RangeObservation, SatId, System};
use raim_proto::frame::encode;
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

#[test]
fn every_frame_is_answered_in_order_with_its_sequence_number() {
    let mut server = Server::new();
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
        (3, 2, 0, 32)
    );
    // Nine sentences per solved epoch of 8 GPS satellites, in order.
    let kinds: Vec<&str> = nmea.lines().map(|l| &l[3..6]).collect();
    let one = [
        "RMC", "VTG", "GGA", "GSA", "GSV", "GSV", "GST", "GBS", "ZDA",
    ];
    assert_eq!(kinds, [one, one].concat());
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

#[test]
fn typed_errors_for_each_kind_of_bad_frame() {
    let mut server = Server::new();
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
    assert!(nmea.is_empty());
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
    assert_eq!(*server.config(), Config::default());
    let ResponseBody::Status(st) = resp[8].body else {
        panic!()
    };
    assert_eq!((st.frames, st.errors), (8, 8));
}

/// Issue 10: the answers are encoded from references (`ResponseRef`);
/// the bytes are those of the owned `Response`, variant by variant.
#[test]
fn body_ref_encodes_as_response_body() {
    let direct = Raim::<CAPACITY, DevicePrecision>::new()
        .process(&Config::default(), &Epoch::linear(1.0, &sky(50.0)))
        .unwrap();
    let mut server = Server::new();
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
            crc32: 0xDEAD_BEEF,
            locked: i % 2 == 0,
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

/// Issue 15: after `Lock` every `Configure` is refused with `Locked`
/// carrying the fingerprint in force, the configuration in force stays,
/// and every answer carries the fingerprint and the lock state.
#[test]
fn a_locked_server_refuses_configure() {
    use raim_core::Phase;
    let terminal = Config::preset(Phase::Terminal);
    let (fp_default, fp_terminal) = (
        raim_proto::config_fingerprint(&Config::default()),
        raim_proto::config_fingerprint(&terminal),
    );
    assert_ne!(fp_default, fp_terminal);
    let mut server = Server::new();
    let default_cfg = Config::default();
    let req = |seq, command| frame(&RequestRef { seq, command });
    let s1 = sky(50.0);
    let mut bytes = req(0, CommandRef::Status);
    bytes.extend(req(1, CommandRef::Configure(&terminal)));
    bytes.extend(req(2, CommandRef::Lock));
    bytes.extend(req(3, CommandRef::Configure(&default_cfg)));
    bytes.extend(req(4, CommandRef::Lock));
    bytes.extend(frame(&RequestRef::linear(5, 1.0, &s1)));
    bytes.extend(req(6, CommandRef::Status));
    let (resp, _) = run(&mut server, &bytes);
    assert_eq!(resp.len(), 7);
    let id = |crc32, locked| ConfigId { crc32, locked };
    let ResponseBody::Status(st0) = resp[0].body else {
        panic!("{:?}", resp[0])
    };
    assert_eq!(st0.config, id(fp_default, false));
    assert_eq!(st0.protocol_version, PROTOCOL_VERSION);
    assert_eq!(resp[1].body, ResponseBody::Configured);
    assert_eq!(resp[1].config, id(fp_terminal, false));
    assert_eq!(resp[2].body, ResponseBody::LockEngaged);
    assert_eq!(resp[2].config, id(fp_terminal, true));
    assert_eq!(
        resp[3].body,
        ResponseBody::Error(WireError::Locked {
            config_crc32: fp_terminal
        })
    );
    assert_eq!(resp[4].body, ResponseBody::LockEngaged);
    let ResponseBody::Result(r) = &resp[5].body else {
        panic!("{:?}", resp[5])
    };
    assert_eq!(resp[5].config, id(fp_terminal, true));
    // The result is the locked (terminal) configuration's.
    let direct = Raim::<CAPACITY, DevicePrecision>::new()
        .process(&terminal, &Epoch::linear(1.0, &s1))
        .unwrap();
    assert_eq!(*r, WireResult::from_result(&direct));
    let ResponseBody::Status(st) = resp[6].body else {
        panic!()
    };
    assert_eq!(st.config, id(fp_terminal, true));
    assert_eq!(*server.config(), terminal);
    // Only a reset (a new server) unlocks.
    assert!(!Server::new().config_id().locked);
}

/// A build with its configuration compiled in refuses `Configure` from
/// the first frame, and refuses to boot with an invalid configuration.
#[test]
fn a_compiled_in_configuration_is_locked_from_boot() {
    let cfg = Config::preset(raim_core::Phase::EnRoute);
    let mut server = Server::new_locked(cfg).unwrap();
    let bytes = frame(&RequestRef {
        seq: 0,
        command: CommandRef::Configure(&Config::default()),
    });
    let (resp, _) = run(&mut server, &bytes);
    let fp = raim_proto::config_fingerprint(&cfg);
    assert_eq!(
        resp[0].body,
        ResponseBody::Error(WireError::Locked { config_crc32: fp })
    );
    assert_eq!(
        resp[0].config,
        ConfigId {
            crc32: fp,
            locked: true
        }
    );
    let bad = Config { pfa: 1e-300, ..cfg };
    assert!(matches!(
        Server::new_locked(bad),
        Err(raim_core::RaimError::OutOfRange { field: "pfa", .. })
    ));
}

/// Issue 15: `Status` carries the platform's reset count and cause; a
/// test fault on a platform without test hooks is refused, typed.
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
    let mut server = Server::new();
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
        &mut Server::new(),
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

/// Issue 15: the platform hears every epoch's verdict (typed errors as
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
    let mut server = Server::new();
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

/// Issue 15: with a key, only an authenticated configuration with a
/// fresh counter is taken; a replayed frame (the same bytes again), a
/// forged tag, a stale counter and a plain `Configure` are refused,
/// typed, and the configuration in force stays.
#[test]
fn authenticated_configure_refuses_replay_and_forgery() {
    use raim_proto::auth::{tag, AuthConfigure};
    let key = [0x5Au8; 32];
    let terminal = Config::preset(raim_core::Phase::Terminal);
    let enroute = Config::preset(raim_core::Phase::EnRoute);
    let signed = |counter, config: Config| AuthConfigure {
        counter,
        config,
        tag: tag(&key, counter, &config),
    };
    let a1 = signed(1, terminal);
    let recorded = frame(&RequestRef {
        seq: 0,
        command: CommandRef::AuthConfigure(&a1),
    });
    let mut forged = signed(2, enroute);
    forged.tag[0] ^= 1;
    let stale = signed(1, enroute);
    let a3 = signed(3, enroute);
    let default_cfg = Config::default();
    let mut server = Server::with_auth_key(key);
    let mut bytes = recorded.clone();
    bytes.extend(recorded.clone()); // the recorded frame, replayed
    for (seq, command) in [
        (1, CommandRef::AuthConfigure(&forged)),
        (2, CommandRef::AuthConfigure(&stale)),
        (3, CommandRef::Configure(&default_cfg)),
    ] {
        bytes.extend(frame(&RequestRef { seq, command }));
    }
    let (resp, _) = run(&mut server, &bytes);
    let bodies: Vec<&ResponseBody> = resp
        .iter()
        .filter(|r| !matches!(r.body, ResponseBody::Error(WireError::SequenceGap { .. })))
        .map(|r| &r.body)
        .collect();
    assert_eq!(
        bodies,
        [
            &ResponseBody::Configured,
            &ResponseBody::Error(WireError::Replayed {
                counter: 1,
                last: 1
            }),
            &ResponseBody::Error(WireError::BadAuthTag { counter: 2 }),
            &ResponseBody::Error(WireError::Replayed {
                counter: 1,
                last: 1
            }),
            &ResponseBody::Error(WireError::AuthRequired),
        ]
    );
    assert_eq!(*server.config(), terminal);
    // A fresh counter is accepted; after Lock even that is refused.
    let mut bytes = frame(&RequestRef {
        seq: 4,
        command: CommandRef::AuthConfigure(&a3),
    });
    bytes.extend(frame(&RequestRef {
        seq: 5,
        command: CommandRef::Lock,
    }));
    let a4 = signed(4, terminal);
    bytes.extend(frame(&RequestRef {
        seq: 6,
        command: CommandRef::AuthConfigure(&a4),
    }));
    let (resp, _) = run(&mut server, &bytes);
    assert_eq!(resp[0].body, ResponseBody::Configured);
    assert_eq!(resp[1].body, ResponseBody::LockEngaged);
    assert!(matches!(
        resp[2].body,
        ResponseBody::Error(WireError::Locked { .. })
    ));
    assert_eq!(*server.config(), enroute);
    // Without a key, authenticated frames are refused, typed.
    let (resp, _) = run(
        &mut Server::new(),
        &frame(&RequestRef {
            seq: 0,
            command: CommandRef::AuthConfigure(&a3),
        }),
    );
    assert_eq!(
        resp[0].body,
        ResponseBody::Error(WireError::AuthNotProvisioned)
    );
}
