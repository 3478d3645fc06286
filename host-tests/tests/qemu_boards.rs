//! The real-board build (`board-stm32f4`, on stm32f4xx-hal) under
//! QEMU's `netduinoplus2` (an STM32F405), through the same runner as the
//! QEMU board (`raim_qemu::Machine`): frames and their answers, results bit
//! for bit as the host core's, the NMEA sentences, and a stream of frames
//! sent back to back. (Its streaming test is in qemu_link.rs, with the QEMU
//! board's.) QEMU does not model this machine's GPIO, RCC or IWDG, so the
//! alarm pin, the clock set-up and the watchdog are tested on mps2-an386
//! only.

mod qemu_common;

use qemu_common::{host_result, range_vectors, session_on, wire_bytes};
use raim_core::{Config, Epoch, FiRule, Phase};
use raim_proto::{ConfigSource, UnitConfigRef, PROTOCOL_VERSION};
use raim_qemu::Machine;

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
