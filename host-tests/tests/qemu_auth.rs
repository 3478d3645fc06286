//! Issue 15: key provisioning in the firmware (firmware/src/key.rs). The
//! build ships without a key and takes plain `Configure`; the same image
//! with a key written into its `.raim_key` section (as production would,
//! `raim_qemu::provision_key`) takes only `AuthConfigure` with a tag made
//! with that key and a counter above the last one it accepted: the right
//! key is accepted, a forged tag, a replayed frame and a stale counter are
//! refused, typed, and the configuration in force stays.

mod qemu_common;

use qemu_common::session;
use raim_core::{Config, Phase};
use raim_proto::auth::{tag, AuthConfigure};
use raim_proto::message::{CommandRef, ResponseBody};
use raim_proto::{config_fingerprint, WireError};
use raim_qemu::QemuSession;

const KEY: [u8; 32] = *b"unit 0042 key, never on the link";

fn signed(key: &[u8; 32], counter: u64, config: Config) -> AuthConfigure {
    AuthConfigure {
        counter,
        config,
        tag: tag(key, counter, &config),
    }
}

#[test]
fn qemu_provisioned_key_accepts_only_authenticated_fresh_configurations() {
    // Without a key: plain Configure is taken, AuthConfigure refused.
    let mut plain = session();
    assert!(!plain.status().unwrap().auth_provisioned);
    let terminal = Config::preset(Phase::Terminal);
    let enroute = Config::preset(Phase::EnRoute);
    assert_eq!(
        plain
            .call(CommandRef::AuthConfigure(&signed(&KEY, 1, terminal)))
            .unwrap(),
        ResponseBody::Error(WireError::AuthNotProvisioned)
    );
    drop(plain);

    let elf = raim_qemu::provision_key(&raim_qemu::firmware_elf().unwrap(), &KEY).unwrap();
    let mut fw = QemuSession::start(&elf).unwrap();
    let st = fw.status().unwrap();
    assert!(st.auth_provisioned);
    let fp = |c: &Config| config_fingerprint(c);
    assert_eq!(st.config.crc32, fp(&Config::default()));
    assert_eq!(
        fw.try_configure(&terminal).unwrap(),
        Err(WireError::AuthRequired)
    );
    // The right key, counter 1: taken.
    let a1 = signed(&KEY, 1, terminal);
    let (seq, recorded) = fw.frame(CommandRef::AuthConfigure(&a1)).unwrap();
    fw.send_raw(&recorded).unwrap();
    let r = fw.recv(raim_qemu::ANSWER_TIMEOUT).unwrap();
    assert_eq!((r.seq, &r.body), (Some(seq), &ResponseBody::Configured));
    assert_eq!(r.config.crc32, fp(&terminal));
    // The recorded frame again, byte for byte: a replay.
    fw.send_raw(&recorded).unwrap();
    let bodies: Vec<ResponseBody> = (0..2)
        .map(|_| fw.recv(raim_qemu::ANSWER_TIMEOUT).unwrap().body)
        .collect();
    assert!(matches!(
        bodies[0],
        ResponseBody::Error(WireError::SequenceGap { .. })
    ));
    assert_eq!(
        bodies[1],
        ResponseBody::Error(WireError::Replayed {
            counter: 1,
            last: 1
        })
    );
    // A tag made with another key: forged.
    let mut other = KEY;
    other[0] ^= 1;
    assert_eq!(
        fw.call(CommandRef::AuthConfigure(&signed(&other, 2, enroute)))
            .unwrap(),
        ResponseBody::Error(WireError::BadAuthTag { counter: 2 })
    );
    // A valid tag on a stale counter.
    assert_eq!(
        fw.call(CommandRef::AuthConfigure(&signed(&KEY, 1, enroute)))
            .unwrap(),
        ResponseBody::Error(WireError::Replayed {
            counter: 1,
            last: 1
        })
    );
    assert_eq!(fw.status().unwrap().config.crc32, fp(&terminal));
    // A fresh counter with the right key: taken.
    assert_eq!(
        fw.call(CommandRef::AuthConfigure(&signed(&KEY, 5, enroute)))
            .unwrap(),
        ResponseBody::Configured
    );
    assert_eq!(fw.status().unwrap().config.crc32, fp(&enroute));
    let _ = std::fs::remove_file(&elf);
}
