//! The server's boot, provisioning, gate and link paths that the frame
//! tests (`tests.rs`) leave out (issue 37, structural coverage): each
//! answer checked against a value the test computes on its own (the
//! fingerprint of what was provisioned, the nonce from its inputs, the
//! byte counts of the frames it sent, the message counts of the RTCM file).
extern crate std;

use std::boxed::Box;
use std::vec::Vec;

use raim_core::pf::PfError;
use raim_core::{Config, LinearObservation, SatId, System};
use raim_proto::auth::{tag, AuthenticatedRef, BootEntropy, ChangeRef};
use raim_proto::frame::{encode, FrameError, FrameReceiver};
use raim_proto::lock::ConfigSource;
use raim_proto::message::{CommandRef, RequestRef, ResetCause, Response, ResponseBody};
#[cfg(feature = "pf")]
use raim_proto::pf_msg::PF_MAX_PARTICLES;
use raim_proto::pf_msg::{PfKind, WirePfConfig};
use raim_proto::unit::{ProvisionError, UnitConfig, UnitConfigRef, UnitPart};

use crate::tests::on_big_stack;
use crate::{check_unit, pf_error, NoPlatform, Platform, Server, UnitRefusal, WireError};
use crate::{CAPACITY, MAX_RESPONSE_FRAME, PROTOCOL_VERSION};

/// A byte sink.
#[derive(Default)]
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

fn frame<T: serde::Serialize>(msg: &T) -> Vec<u8> {
    let mut scratch = [0u8; 4096];
    let mut out = [0u8; 4096];
    encode(msg, &mut scratch, &mut out).unwrap().to_vec()
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

/// Feeds `bytes`, then a pause when `idle`; the answers and the NMEA text.
fn run_idle(server: &mut Server, bytes: &[u8], idle: bool) -> (Vec<Response>, std::string::String) {
    let (mut link, mut nmea) = (Sink::default(), Sink::default());
    for &b in bytes {
        server
            .on_byte(b, &mut link, &mut nmea, &mut NoPlatform)
            .unwrap();
    }
    if idle {
        server
            .on_line_idle(&mut link, &mut nmea, &mut NoPlatform)
            .unwrap();
    }
    (
        responses(&link.0),
        std::string::String::from_utf8(nmea.0).unwrap(),
    )
}

fn run(server: &mut Server, bytes: &[u8]) -> Vec<Response> {
    run_idle(server, bytes, false).0
}

fn status(seq: u32) -> Vec<u8> {
    frame(&RequestRef {
        seq,
        command: CommandRef::Status,
    })
}

/// Six satellites, each with a host sigma.
fn sky() -> Vec<LinearObservation> {
    [
        (0.0, 80.0),
        (60.0, 30.0),
        (120.0, 45.0),
        (180.0, 20.0),
        (240.0, 60.0),
        (300.0, 35.0),
    ]
    .iter()
    .enumerate()
    .map(|(i, &(az, el)): (usize, &(f64, f64))| {
        let mut o = LinearObservation::from_az_el(
            SatId::new(System::Gps, i as u8 + 1),
            f64::to_radians(az),
            f64::to_radians(el),
            0.0,
        );
        o.sigma_m = Some(1.0);
        o
    })
    .collect()
}

fn entropy() -> BootEntropy {
    BootEntropy {
        bytes: [9; 32],
        hardware: true,
    }
}

fn unit(snapshot: Option<Config>, pf: Option<WirePfConfig>, host_sigmas: bool) -> UnitConfig {
    UnitConfig {
        snapshot,
        araim: None,
        pf,
        host_sigmas,
        model_check: raim_proto::WireModelCheckConfig::DEFAULT,
    }
}

fn pf_config(particles: u32) -> WirePfConfig {
    WirePfConfig {
        kind: PfKind::Gapf,
        particles,
        seed: 3,
        config: raim_core::pf::PfConfig {
            sigma_m: 3.0,
            mutation_m: 0.5,
            window: 8,
            pfa: 1e-3,
            ..raim_core::pf::PfConfig::default()
        },
    }
}

/// A provisioned unit puts its configuration in force, locked, with the
/// fingerprint of exactly what was provisioned; it then refuses every
/// change (`Locked` with that fingerprint), a plain `Lock` included, and
/// an epoch carrying a host sigma when the unit takes none
/// (`HostSigmaRefused` naming the first such satellite).
///
/// Verifies: SAFE-PROVISION, WIRE-Locked, WIRE-HostSigmaRefused
#[test]
fn a_provisioned_unit_runs_locked_and_refuses_host_sigmas() {
    on_big_stack(|| {
        let config = Config {
            pfa: 2e-3,
            ..Config::default()
        };
        let want = UnitConfigRef {
            snapshot: Some(&config),
            araim: None,
            pf: None,
            host_sigmas: false,
            model_check: &raim_proto::WireModelCheckConfig::DEFAULT,
        }
        .fingerprint();
        let mut s = Box::new(Server::new());
        s.boot(Ok(Some(unit(Some(config), None, false))), 4, &entropy());
        let id = s.config_id();
        assert_eq!(id.fingerprint, want);
        assert!(id.locked);
        assert_eq!(id.source, ConfigSource::Provisioned);
        assert_eq!(s.config(), Some(&config));
        assert_eq!(s.status().provision_error, None);
        assert!(!s.status().host_sigmas);

        let sats = sky();
        let mut bytes = frame(&RequestRef::linear(0, 0.0, &sats));
        bytes.extend(frame(&RequestRef {
            seq: 1,
            command: CommandRef::Lock,
        }));
        bytes.extend(frame(&RequestRef {
            seq: 2,
            command: CommandRef::HostSigmas(true),
        }));
        let answers = run(&mut s, &bytes);
        assert_eq!(answers.len(), 3);
        assert_eq!(
            answers[0].body,
            ResponseBody::Error(WireError::HostSigmaRefused { index: 0 })
        );
        for a in &answers[1..] {
            assert_eq!(
                a.body,
                ResponseBody::Error(WireError::Locked { fingerprint: want })
            );
        }
        assert!(!s.status().host_sigmas);
    })
}

/// Each part of a unit configuration is checked as its runtime change is:
/// the first failing part and that part's own error (a snapshot outside
/// its bounds, an ISM list longer than it holds, a particle count not
/// compiled in); a valid unit passes.
///
/// Verifies: SAFE-PROVISION
#[test]
fn check_unit_names_the_first_failing_part_and_its_error() {
    let bad_snapshot = Config {
        pfa: 2.0,
        ..Config::default()
    };
    let snapshot_error: WireError = bad_snapshot.validate().unwrap_err().into();
    assert_eq!(
        check_unit(&unit(Some(bad_snapshot), Some(pf_config(7)), true)),
        Err(UnitRefusal {
            part: UnitPart::Snapshot,
            error: snapshot_error,
        })
    );
    // A build without the particle filter refuses any PF part as
    // unavailable; one with it, the particle count it does not hold.
    #[cfg(feature = "pf")]
    let pf_error = WireError::PfParticles {
        requested: 7,
        max: PF_MAX_PARTICLES,
    };
    #[cfg(not(feature = "pf"))]
    let pf_error = WireError::PfUnavailable;
    assert_eq!(
        check_unit(&unit(Some(Config::default()), Some(pf_config(7)), true)),
        Err(UnitRefusal {
            part: UnitPart::Pf,
            error: pf_error,
        })
    );
    let mut araim = unit(None, None, true);
    araim.araim = Some(raim_proto::araim_msg::IsmFrame {
        config: raim_proto::araim_msg::WireAraimConfig::default(),
        p_const: [None; raim_core::measurement::MAX_SYSTEMS],
        sats: raim_proto::message::SatList {
            items: heapless::Vec::new(),
            declared: 100,
        },
    });
    assert_eq!(
        check_unit(&araim),
        Err(UnitRefusal {
            part: UnitPart::Araim,
            error: WireError::TooManySatellites {
                have: 100,
                capacity: CAPACITY as u32,
            },
        })
    );
    #[cfg(feature = "pf")]
    assert_eq!(check_unit(&unit(None, Some(pf_config(100)), false)), Ok(()));
    assert_eq!(check_unit(&unit(None, None, true)), Ok(()));
}

/// A provisioned section whose part fails its checks leaves the unit
/// Unconfigured and locked, the part named in `Status`, the boot notice
/// and every refusal; a valid PF part on a unit without PF engines fails
/// the same way (nothing of it goes in force).
///
/// Verifies: SAFE-PROVISION, WIRE-Unconfigured
#[test]
fn a_refused_part_leaves_the_unit_unconfigured_and_locked() {
    on_big_stack(|| {
        let bad = Config {
            pfa: 2.0,
            ..Config::default()
        };
        let mut s = Box::new(Server::new());
        assert_eq!(
            s.provision(unit(Some(bad), None, true)),
            Err(ProvisionError::InvalidPart(UnitPart::Snapshot))
        );
        // A valid PF part, but no engine to run it.
        assert_eq!(
            s.provision(unit(Some(Config::default()), Some(pf_config(100)), true)),
            Err(ProvisionError::InvalidPart(UnitPart::Pf))
        );
        assert_eq!(s.config(), None);
        assert_eq!(s.pf_config(), None);

        let mut s = Box::new(Server::new());
        s.boot(Ok(Some(unit(Some(bad), None, true))), 0, &entropy());
        let e = ProvisionError::InvalidPart(UnitPart::Snapshot);
        assert_eq!(s.status().provision_error, Some(e));
        assert!(s.config_id().locked);
        assert_eq!(s.config_id().source, ConfigSource::Unconfigured);
        let answers = run(
            &mut s,
            &frame(&RequestRef {
                seq: 0,
                command: CommandRef::Configure(&Config::default()),
            }),
        );
        assert_eq!(
            answers[0].body,
            ResponseBody::Error(WireError::Unconfigured { provision: Some(e) })
        );
    })
}

/// A PF part with its engine attached goes in force with the unit, and
/// the fingerprint covers it.
#[cfg(feature = "pf")]
#[test]
fn a_provisioned_pf_part_goes_in_force() {
    on_big_stack(|| {
        use raim_core::pf::PfRaim;
        fn leak<T>(t: T) -> Option<&'static mut T> {
            Some(Box::leak(Box::new(t)))
        }
        let mut s = Box::new(Server::new());
        s.attach_pf(crate::PfEngines {
            ekf: None,
            pf100: None,
            pf300: None,
            ga100: leak(PfRaim::new(0)),
            ga300: None,
        });
        let pf = pf_config(100);
        assert_eq!(s.provision(unit(None, Some(pf), true)), Ok(()));
        assert_eq!(s.pf_config(), Some(&pf));
        let want = UnitConfigRef {
            snapshot: None,
            araim: None,
            pf: Some(&pf),
            host_sigmas: true,
            model_check: &raim_proto::WireModelCheckConfig::DEFAULT,
        }
        .fingerprint();
        assert_eq!(s.config_id().fingerprint, want);
        assert_eq!(s.config_id().source, ConfigSource::Provisioned);
    })
}

/// The boot notice carries the reset record the platform gives, the
/// provisioning error, the key's presence and the nonce that
/// `auth::boot_nonce` derives from the same inputs.
#[test]
fn the_boot_notice_carries_the_boot_record() {
    on_big_stack(|| {
        struct Resets;
        impl Platform for Resets {
            fn now(&mut self) -> u32 {
                0
            }
            fn reset_record(&mut self) -> (u32, ResetCause) {
                (3, ResetCause::Watchdog { pc: 0x0800_1234 })
            }
        }
        let mut s = Box::new(Server::with_auth_key([1; 32]));
        s.boot(Err(ProvisionError::BadSeal), 3, &entropy());
        let nonce = raim_proto::auth::boot_nonce(Some(&[1; 32]), 3, None, &[9; 32]);
        assert_eq!(s.nonce(), nonce);
        let mut link = Sink::default();
        s.send_boot_notice::<_, core::convert::Infallible, _>(&mut link, &mut Resets)
            .unwrap();
        let answers = responses(&link.0);
        assert_eq!(answers.len(), 1);
        assert_eq!(answers[0].seq, None);
        let ResponseBody::Boot(b) = &answers[0].body else {
            panic!("{:?}", answers[0])
        };
        assert_eq!(b.protocol_version, PROTOCOL_VERSION);
        assert_eq!(
            (b.resets, b.reset_cause),
            (3, ResetCause::Watchdog { pc: 0x0800_1234 })
        );
        assert_eq!(b.provision_error, Some(ProvisionError::BadSeal));
        assert!(b.auth_provisioned);
        assert_eq!(b.boot_nonce, nonce);
        assert!(b.config.locked);
        assert_eq!(b.config.source, ConfigSource::Unconfigured);
        assert!(s.status().hardware_entropy);
    })
}

/// The counter's last value is never taken, even under a good tag: the
/// next counter would not exist (`CounterExhausted` with the value).
///
/// Verifies: WIRE-CounterExhausted
#[test]
fn the_last_counter_value_is_refused() {
    on_big_stack(|| {
        let mut s = Box::new(Server::with_auth_key([7; 32]));
        s.boot(Ok(None), 0, &entropy());
        let change = ChangeRef::HostSigmas(false);
        let counter = u64::MAX;
        let a = AuthenticatedRef {
            counter,
            change,
            tag: tag(&[7; 32], &s.nonce(), counter, &change),
        };
        let answers = run(
            &mut s,
            &frame(&RequestRef {
                seq: 0,
                command: CommandRef::Authenticated(a),
            }),
        );
        assert_eq!(
            answers[0].body,
            ResponseBody::Error(WireError::CounterExhausted { counter })
        );
        assert!(s.status().host_sigmas);
    })
}

/// An open bench unit takes `HostSigmas(false)`, after which an epoch
/// with a host sigma is refused naming it; a plain `Lock` with a
/// configuration in force engages the lock.
///
/// Verifies: WIRE-HostSigmaRefused
#[test]
fn host_sigmas_off_refuses_the_first_sigma_and_lock_engages() {
    on_big_stack(|| {
        let mut s = Box::new(Server::new());
        s.take_runtime_config(Config::default()).unwrap();
        let mut sats = sky();
        sats[0].sigma_m = None;
        sats[1].sigma_m = None;
        let mut bytes = frame(&RequestRef {
            seq: 0,
            command: CommandRef::HostSigmas(false),
        });
        bytes.extend(frame(&RequestRef::linear(1, 0.0, &sats)));
        bytes.extend(frame(&RequestRef {
            seq: 2,
            command: CommandRef::Lock,
        }));
        let answers = run(&mut s, &bytes);
        assert_eq!(answers[0].body, ResponseBody::Configured);
        assert_eq!(
            answers[1].body,
            ResponseBody::Error(WireError::HostSigmaRefused { index: 2 })
        );
        assert_eq!(answers[2].body, ResponseBody::LockEngaged);
        assert!(s.config_id().locked);
        assert_eq!(s.config_id().source, ConfigSource::Runtime);
    })
}

/// A frame whose envelope verifies but whose payload is no request is
/// refused `Undecodable` with the payload's length and the sequence
/// number it starts with; its no-fix sentences go out.
///
/// Verifies: WIRE-Undecodable
#[test]
fn a_payload_that_is_no_request_keeps_its_sequence_number() {
    on_big_stack(|| {
        let mut s = Box::new(Server::new());
        s.take_runtime_config(Config::default()).unwrap();
        // postcard: the varint 5 (1 byte), then the varint 250 (2 bytes),
        // a command index past the last variant.
        let (answers, nmea) = run_idle(&mut s, &frame(&(5u32, 250u32)), false);
        assert_eq!(answers.len(), 1);
        assert_eq!(answers[0].seq, Some(5));
        assert_eq!(
            answers[0].body,
            ResponseBody::Error(WireError::from(FrameError::Undecodable { len: 3 }))
        );
        assert!(nmea.contains("GGA"), "{nmea}");
    })
}

/// A pause ends an open frame (`on_line_idle`): half a frame is answered
/// as an unreadable one, and a full frame after it is answered normally.
#[test]
fn a_pause_ends_a_half_frame() {
    on_big_stack(|| {
        let mut s = Box::new(Server::new());
        s.take_runtime_config(Config::default()).unwrap();
        let f = status(0);
        let (answers, _) = run_idle(&mut s, &f[..f.len() / 2], true);
        assert_eq!(answers.len(), 1);
        assert_eq!(answers[0].seq, None);
        assert!(
            matches!(answers[0].body, ResponseBody::Error(_)),
            "{:?}",
            answers[0]
        );
        // A pause with nothing open answers nothing.
        let (answers, _) = run_idle(&mut s, &[], true);
        assert!(answers.is_empty());
        let (answers, _) = run_idle(&mut s, &status(1), false);
        assert_eq!(answers.len(), 1);
        assert!(matches!(answers[0].body, ResponseBody::Status(_)));
    })
}

/// A stray RTCM header (`D3 03 FF`: 1023 + 6 bytes declared) with a few
/// bytes of noise before a host frame: the bytes before the frame are
/// answered `TruncatedRtcm` (how many, and the length declared), then the
/// frame itself.
///
/// Verifies: WIRE-TruncatedRtcm
#[test]
fn a_stray_rtcm_header_before_a_frame_is_answered_truncated() {
    on_big_stack(|| {
        let mut s = Box::new(Server::new());
        s.take_runtime_config(Config::default()).unwrap();
        let mut bytes = std::vec![0xD3, 0x03, 0xFF, 0x11, 0x22, 0x33, 0x44];
        let stray = bytes.len() as u32;
        bytes.extend(status(0));
        let answers = run(&mut s, &bytes);
        assert_eq!(answers.len(), 2, "{answers:?}");
        assert_eq!(answers[0].seq, None);
        assert_eq!(
            answers[0].body,
            ResponseBody::Error(WireError::TruncatedRtcm {
                received: stray,
                declared: 1023 + 6,
            })
        );
        assert_eq!(answers[1].seq, Some(0));
        assert!(matches!(answers[1].body, ResponseBody::Status(_)));
    })
}

/// The PF errors on the wire keep their offending values (the variants
/// the wire tests do not reach through an epoch).
///
/// Verifies: WIRE-PfInvalidConfig, WIRE-NoConvergence, WIRE-SigmaOutOfRange, WIRE-PrnOutOfRange
#[test]
fn pf_errors_keep_their_values_on_the_wire() {
    let e = pf_error(
        PfError::NotCalibrated {
            field: "window",
            value: 9.0,
        },
        &[],
    );
    assert!(
        matches!(e, WireError::PfInvalidConfig { value, .. } if value == 9.0),
        "{e:?}"
    );
    assert_eq!(
        pf_error(
            PfError::NoInitialFix {
                iterations: 20,
                step_m: 3.5
            },
            &[]
        ),
        WireError::NoConvergence {
            iterations: 20,
            step_m: 3.5
        }
    );
    assert_eq!(
        pf_error(
            PfError::SigmaOutOfRange {
                index: 4,
                sigma_m: 1e9,
                min_m: 0.01,
                max_m: 1e4,
            },
            &[]
        ),
        WireError::SigmaOutOfRange {
            index: 4,
            sigma_m: 1e9,
            min_m: 0.01,
            max_m: 1e4,
        }
    );
    let id = SatId::new(System::Gps, 77);
    assert_eq!(
        pf_error(
            PfError::PrnOutOfRange {
                index: 2,
                id,
                max: 32
            },
            &[]
        ),
        WireError::PrnOutOfRange {
            index: 2,
            id,
            max: 32
        }
    );
}

#[cfg(feature = "rtcm")]
/// GMSD7 (2012-10-14; GPS, GLONASS and BeiDou MSM7, one GPS MSM7 a
/// epoch), `/work/shared/data/GMSD7_20121014.rtcm3`.
fn gmsd7() -> Vec<u8> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/GMSD7_20121014.rtcm3"
    );
    std::fs::read(path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

#[cfg(feature = "rtcm")]
/// The message numbers (DF002) of the RTCM 3 frames of `bytes`, by the
/// framing of RTCM 10403.3 alone (preamble 0xD3, a 10-bit length, the
/// payload, 3 CRC bytes), without the receiver under test.
fn message_numbers(bytes: &[u8]) -> Vec<u16> {
    let mut out = Vec::new();
    let mut i = 0;
    while i + 5 <= bytes.len() {
        if bytes[i] != 0xD3 {
            i += 1;
            continue;
        }
        let len = (usize::from(bytes[i + 1] & 0x03) << 8) | usize::from(bytes[i + 2]);
        if i + 6 + len > bytes.len() {
            break;
        }
        out.push((u16::from(bytes[i + 3]) << 4) | (u16::from(bytes[i + 4]) >> 4));
        i += 6 + len;
    }
    out
}

#[cfg(feature = "rtcm")]
/// The stream answers of `bytes` fed to `server` with a pause after each
/// RTCM frame (a receiver's burst): the unasked answers, and the NMEA.
fn stream(server: &mut Server, bytes: &[u8]) -> (Vec<Response>, std::string::String) {
    let (answers, nmea) = run_idle(server, bytes, true);
    assert!(answers.iter().all(|a| a.seq.is_none()), "{answers:?}");
    (answers, nmea)
}

#[cfg(feature = "rtcm")]
/// An RTCM 3 frame around `payload` (RTCM 10403.3 §4: preamble 0xD3, six
/// zero bits, the 10-bit length, the payload, CRC-24Q over all of it;
/// the CRC written out here, polynomial 0x864CFB, initial value 0).
fn rtcm_frame(payload: &[u8]) -> Vec<u8> {
    let mut f = std::vec![0xD3, (payload.len() >> 8) as u8 & 0x03, payload.len() as u8];
    f.extend_from_slice(payload);
    let mut crc = 0u32;
    for &b in &f {
        crc ^= u32::from(b) << 16;
        for _ in 0..8 {
            crc <<= 1;
            if crc & 0x0100_0000 != 0 {
                crc ^= 0x0186_4CFB;
            }
        }
    }
    f.extend_from_slice(&[(crc >> 16) as u8, (crc >> 8) as u8, crc as u8]);
    f
}

#[cfg(feature = "rtcm")]
/// An RTCM 1013 (system parameters, RTCM 10403.3 §3.5.5: DF002 12, DF003
/// 12, DF051 MJD 16, DF052 UTC second of day 17, DF053 5 (no message
/// entries), DF054 GPS - UTC 8 bits, padded to a whole byte).
fn msg1013(mjd: u32, leap_s: u32) -> Vec<u8> {
    let fields: [(u64, u32); 6] = [
        (1013, 12),
        (0, 12),
        (u64::from(mjd), 16),
        (0, 17),
        (0, 5),
        (u64::from(leap_s), 8),
    ];
    let mut bits: u128 = 0;
    let mut n = 0;
    for (v, w) in fields {
        bits = (bits << w) | u128::from(v);
        n += w;
    }
    bits <<= 72 - n;
    rtcm_frame(&bits.to_be_bytes()[16 - 9..])
}

/// RTCM 3 straight into the unit (the link's RTCM frames), GMSD7 after an
/// RTCM 1013 that gives GPS - UTC = 16 s (2012): every epoch the stream
/// closes (one a GPS MSM7, 1077, in GMSD7) is answered unasked, once, and
/// `Status` counts them; the epochs before the first GPS ephemeris (1019)
/// are refused `StreamNotDated`, and `Status` reports the stream's leap
/// seconds; every later epoch runs the monitor. With no configuration in force every formed epoch is refused
/// `Unconfigured` (a stream never puts a default in force). The 1013 is
/// needed here: this build dates GMSD7 1024 weeks late (its pivot is the
/// build date less a year), past the built-in leap-second table.
///
/// Verifies: RX-STREAM, RX-LEAP, WIRE-Unconfigured, WIRE-StreamNotDated
#[test]
#[cfg(feature = "rtcm")]
fn stream_epochs_through_the_link_are_answered_unasked() {
    on_big_stack(|| {
        const EPOCHS: usize = 60;
        let bytes = gmsd7();
        // The frames of the first EPOCHS epochs (debug-build time), up to
        // the next epoch's 1077.
        let mut part = msg1013(56_214, 16);
        let (mut epochs, mut i) = (0, 0);
        let mut dated = None;
        while i + 5 <= bytes.len() {
            let len = (usize::from(bytes[i + 1] & 0x03) << 8) | usize::from(bytes[i + 2]);
            let n = message_numbers(&bytes[i..i + 6 + len])[0];
            if n == 1077 {
                if epochs == EPOCHS {
                    break;
                }
                epochs += 1;
            }
            // The first epoch the 1019 arrives in (before its 1077) or
            // the next one (after it) is dated.
            if n == 1019 && dated.is_none() {
                dated = Some(epochs);
            }
            part.extend_from_slice(&bytes[i..i + 6 + len]);
            i += 6 + len;
        }
        assert_eq!(epochs, EPOCHS);
        let dated = dated.unwrap();

        let mut s = Box::new(Server::new());
        s.take_runtime_config(Config::default()).unwrap();
        let (answers, nmea) = stream(&mut s, &part);
        assert_eq!(answers.len(), EPOCHS);
        let not_dated = answers
            .iter()
            .filter(|a| {
                matches!(
                    a.body,
                    ResponseBody::Error(WireError::StreamNotDated { .. })
                )
            })
            .count();
        assert!(
            not_dated == dated || not_dated == dated + 1,
            "{not_dated} {dated}"
        );
        // Every dated epoch ran the monitor: a result, or the engine's
        // own refusal (this build's dating leaves few satellites above
        // the mask in GMSD7's first minute), never a stream refusal.
        for a in &answers[not_dated..] {
            assert!(
                matches!(
                    a.body,
                    ResponseBody::Result(_)
                        | ResponseBody::Error(WireError::TooFewSatellites { .. })
                ),
                "{a:?}"
            );
        }
        assert_eq!(nmea.matches("GGA").count(), EPOCHS, "{nmea}");
        let answer = run(&mut s, &status(0));
        let ResponseBody::Status(st) = &answer[0].body else {
            panic!("{answer:?}")
        };
        assert_eq!(st.stream_epochs as usize, EPOCHS);
        assert_eq!(
            st.stream_leap_seconds,
            raim_proto::message::StreamLeapSeconds::Stream {
                gps_minus_utc_s: 16
            }
        );

        // Without the 1013 this build has no GPS - UTC for 2032: past
        // the table, reported as such.
        let mut t = Box::new(Server::new());
        t.take_runtime_config(Config::default()).unwrap();
        let _ = stream(&mut t, &part[msg1013(56_214, 16).len()..]);
        let answer = run(&mut t, &status(0));
        let ResponseBody::Status(st) = &answer[0].body else {
            panic!("{answer:?}")
        };
        assert_eq!(
            st.stream_leap_seconds,
            raim_proto::message::StreamLeapSeconds::TableExpired
        );

        let mut u = Box::new(Server::new());
        let (answers, _) = stream(&mut u, &part);
        assert_eq!(answers.len(), EPOCHS);
        let unconfigured = answers
            .iter()
            .filter(|a| a.body == ResponseBody::Error(WireError::Unconfigured { provision: None }))
            .count();
        assert_eq!(unconfigured, EPOCHS - not_dated);
    })
}

/// A UART that takes nothing.
struct Broken;
impl embedded_io::ErrorType for Broken {
    type Error = embedded_io::ErrorKind;
}
impl embedded_io::Write for Broken {
    fn write(&mut self, _: &[u8]) -> Result<usize, Self::Error> {
        Err(embedded_io::ErrorKind::Other)
    }
    fn flush(&mut self) -> Result<(), Self::Error> {
        Err(embedded_io::ErrorKind::Other)
    }
}

/// A UART that fails is reported, typed, as the one it is: the NMEA
/// port's failure when an epoch's sentences go out, the link's when an
/// answer does.
#[test]
fn a_failing_uart_is_reported_as_itself() {
    on_big_stack(|| {
        let sats = sky();
        let bytes = frame(&RequestRef::linear(0, 0.0, &sats));
        let mut s = Box::new(Server::new());
        s.take_runtime_config(Config::default()).unwrap();
        let mut link = Sink::default();
        let mut errors = Vec::new();
        for &b in &bytes {
            if let Err(e) = s.on_byte(b, &mut link, &mut Broken, &mut NoPlatform) {
                errors.push(e);
            }
        }
        assert_eq!(
            errors,
            [crate::IoError::Nmea(embedded_io::ErrorKind::Other)]
        );

        let mut s = Box::new(Server::new());
        let mut errors = Vec::new();
        for &b in &status(0) {
            if let Err(e) = s.on_byte(b, &mut Broken, &mut Sink::default(), &mut NoPlatform) {
                errors.push(e);
            }
        }
        assert_eq!(
            errors,
            [crate::IoError::Link(embedded_io::ErrorKind::Other)]
        );
    })
}

/// The boot notice by reference encodes as the `ResponseBody` it stands
/// for, byte for byte (postcard: the variant index, then the payload).
#[test]
fn a_boot_notice_by_reference_encodes_as_its_body() {
    let notice = raim_proto::BootNotice {
        protocol_version: PROTOCOL_VERSION,
        resets: 2,
        reset_cause: ResetCause::Unrecorded,
        config: Server::new().config_id(),
        provision_error: Some(ProvisionError::BadMagic),
        auth_provisioned: true,
        boot_nonce: [3; 16],
    };
    let body = ResponseBody::Boot(notice);
    let by_ref = crate::answer::BodyRef::from(&body);
    let (mut a, mut b) = ([0u8; 256], [0u8; 256]);
    assert_eq!(
        postcard::to_slice(&by_ref, &mut a).unwrap(),
        postcard::to_slice(&body, &mut b).unwrap()
    );
}

/// A unit with a runtime change in force but no snapshot configuration
/// (only `HostSigmas`) is not Unconfigured as a whole, yet its snapshot
/// epochs are: they are refused `Unconfigured`, never run on a default.
///
/// Verifies: WIRE-Unconfigured
#[test]
fn a_snapshot_epoch_needs_the_snapshot_configuration() {
    on_big_stack(|| {
        let mut s = Box::new(Server::new());
        let mut sats = sky();
        for o in &mut sats {
            o.sigma_m = None;
        }
        let mut bytes = frame(&RequestRef {
            seq: 0,
            command: CommandRef::HostSigmas(false),
        });
        bytes.extend(frame(&RequestRef::linear(1, 0.0, &sats)));
        let answers = run(&mut s, &bytes);
        assert_eq!(answers[0].body, ResponseBody::Configured);
        assert_eq!(s.config_id().source, ConfigSource::Runtime);
        assert_eq!(s.config(), None);
        assert_eq!(
            answers[1].body,
            ResponseBody::Error(WireError::Unconfigured { provision: None })
        );
    })
}
