//! The real-board build (`board-stm32f4`, on stm32f4xx-hal) under
//! QEMU's `netduinoplus2` (an STM32F405), through the same runner as the
//! QEMU board (`raim_qemu::Machine`): frames and their answers, results bit
//! for bit as the host core's, the NMEA sentences, and a stream of frames
//! sent back to back. (Its streaming test is in qemu_link.rs, with the QEMU
//! board's.) QEMU does not model this machine's GPIO, RCC or IWDG, so the
//! alarm pin and the watchdog are tested on mps2-an386 only; its RCC reads
//! 0, so the clock set-up always takes its HSI fallback here, which the
//! `Status` clock fields show.

mod qemu_common;

use qemu_common::{host_result, range_vectors, session_on, wire_bytes};
use raim_core::{Config, Epoch, FiRule, Phase};
use raim_proto::{ConfigSource, EpochCycles, UnitConfigRef, PROTOCOL_VERSION};
use raim_qemu::Machine;

/// The clock each board reports in `Status`: mps2-an386 its fixed 25 MHz;
/// the STM32F4 build, whose HSE never becomes ready under QEMU (the RCC
/// is unimplemented there and reads 0), the 16 MHz HSI, flagged as the
/// fallback, after its bounded wait ran out (and it still answers).
#[test]
fn qemu_boards_report_the_core_clock_they_run_at() {
    let mut mps2 = session_on(Machine::Mps2An386);
    let st = mps2.status().unwrap();
    assert_eq!((st.core_clock_hz, st.clock_fallback), (25_000_000, false));
    drop(mps2);
    let mut f4 = session_on(Machine::NetduinoPlus2);
    let st = f4.status().unwrap();
    assert_eq!((st.core_clock_hz, st.clock_fallback), (16_000_000, true));
    // The host's server has no board: no clock.
    let host = raim_server::Server::new().status();
    assert_eq!((host.core_clock_hz, host.clock_fallback), (0, false));
}

/// Neither QEMU machine models the DWT cycle counter (QEMU reads its
/// registers as 0 and ignores writes): after epochs have run and been
/// timed in ticks, both boards' `Status` says their epochs' cycles are
/// not measured, never a zero count; so does the host's server, which
/// has no counter. (On a real board the counter runs: the server's unit
/// test `status_reports_epoch_cycles_when_the_counter_runs_...` checks
/// what it then reports.)
///
/// Verifies: FW-CYCLES
#[test]
fn qemu_boards_say_their_epoch_cycles_are_not_measured() {
    for machine in [Machine::Mps2An386, Machine::NetduinoPlus2] {
        let mut fw = session_on(machine);
        let cfg = Config::preset(Phase::Terminal);
        fw.configure(&cfg).unwrap();
        for (time_s, sats, apriori) in range_vectors(3).iter().take(3) {
            fw.process(&Epoch::ranges(*time_s, sats, *apriori)).unwrap();
        }
        let st = fw.status().unwrap();
        // The DWT accesses at boot did not fault (QEMU logs them as
        // unassigned; a fault would have reset the unit).
        assert_eq!((st.epochs, st.resets), (3, 0), "{machine:?}");
        assert!(st.last_epoch_ticks > 0, "{machine:?}: the epoch was timed");
        assert_eq!(st.epoch_cycles, EpochCycles::NotMeasured, "{machine:?}");
    }
    let host = raim_server::Server::new().status();
    assert_eq!(host.epoch_cycles, EpochCycles::NotMeasured);
}

/// Neither QEMU machine gives the boot nonce hardware entropy:
/// mps2-an386 has no RNG; netduinoplus2 does not model the STM32F4's (nor
/// the PLL that clocks it, which never locks there), so the firmware's
/// bounded start of it gives up and the unit says so. Under `-icount` two
/// power-ons of the same image boot alike, and their nonces coincide: the
/// replay across power cycles that `hardware_entropy: false` warns of
/// (docs/SAFETY.md "Boot nonce"). The host's server reports the source it
/// was booted with.
///
/// Verifies: SAFE-T10
#[test]
fn qemu_boards_say_their_boot_nonce_had_no_hardware_entropy() {
    for machine in [Machine::Mps2An386, Machine::NetduinoPlus2] {
        let elf = raim_qemu::firmware_elf_for(machine).unwrap();
        let opts = raim_qemu::Options {
            machine,
            icount: true,
            ..raim_qemu::Options::default()
        };
        let nonces: Vec<_> = (0..2)
            .map(|_| {
                let mut fw = raim_qemu::QemuSession::start_with(&elf, &opts).unwrap();
                let st = fw.status().unwrap();
                assert!(!st.hardware_entropy, "{machine:?}");
                assert_eq!(st.resets, 0, "{machine:?}");
                st.boot_nonce
            })
            .collect();
        assert_eq!(nonces[0], nonces[1], "{machine:?}");
    }
    let host = raim_server::Server::new().status();
    assert!(!host.hardware_entropy);
    let mut booted = Box::new(raim_server::Server::new());
    let entropy = raim_proto::auth::BootEntropy {
        bytes: [3; 32],
        hardware: true,
    };
    booted.boot(Ok(None), 0, &entropy);
    assert!(booted.status().hardware_entropy);
}

#[test]
fn qemu_netduinoplus2_answers_frames_bit_for_bit_with_nmea() {
    let mut fw = session_on(Machine::NetduinoPlus2);
    let st = fw.status().unwrap();
    assert_eq!(st.protocol_version, PROTOCOL_VERSION);
    // The session set the unprovisioned unit up as a bench host does.
    let bench = UnitConfigRef {
        snapshot: Some(&Config::default()),
        araim: None,
        pf: None,
        host_sigmas: true,
        model_check: &raim_proto::WireModelCheckConfig::DEFAULT,
    };
    assert_eq!(st.config.fingerprint, bench.fingerprint());
    assert_eq!(st.config.source, ConfigSource::Runtime);
    assert!(!st.config.locked);
    let mut compared = 0;
    for (k, rule) in [FiRule::Mle, FiRule::LraimGaussian { kappa: 30.0 }]
        .into_iter()
        .enumerate()
    {
        let cfg = Config {
            rule,
            ..Config::preset(Phase::Terminal)
        };
        fw.configure(&cfg).unwrap();
        for (i, (time_s, sats, apriori)) in range_vectors(k as u64).iter().enumerate() {
            let epoch = Epoch::ranges(*time_s, sats, *apriori);
            let p = fw.process(&epoch).unwrap();
            let host = host_result(&cfg, &epoch);
            match (&p.outcome, &host) {
                (Ok(fw_r), Ok(host_r)) => {
                    assert_eq!(wire_bytes(fw_r), wire_bytes(host_r), "rule {k} epoch {i}");
                    // The same five sentences the host's writer makes.
                    let want: Vec<String> = raim_proto::nmea::epoch_sentences(
                        host_r,
                        &raim_proto::nmea::Sky::new(&epoch),
                        raim_proto::nmea::BUILT,
                    )
                    .unwrap()
                    .iter()
                    .map(|s| s.trim_end().to_string())
                    .collect();
                    assert_eq!(p.nmea, want, "rule {k} epoch {i}");
                }
                // A refused epoch writes its no-fix sentences.
                (Err(_), Err(_)) => assert!(p
                    .nmea
                    .iter()
                    .all(|s| !s.contains("RMC,") || s.split(',').nth(2) == Some("V"))),
                (a, b) => panic!("rule {k} epoch {i}: firmware {a:?}, host {b:?}"),
            }
            compared += 1;
        }
    }
    assert!(compared >= 12, "{compared}");
    let st = fw.status().unwrap();
    assert_eq!(st.uart_overruns, 0);
    assert_eq!(st.epochs, compared);
}
