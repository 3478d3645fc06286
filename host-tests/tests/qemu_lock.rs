//! Issue 15: a locked unit refuses `Configure` over the wire, under QEMU,
//! and every answer carries the fingerprint of the configuration in force
//! and the lock state.

mod qemu_common;

use qemu_common::{host_result, range_vectors, session, wire_bytes};
use raim_core::{Config, Epoch, Phase};
use raim_proto::{config_fingerprint, ConfigId, WireError, PROTOCOL_VERSION};

#[test]
fn qemu_locked_unit_refuses_configure() {
    let mut fw = session();
    let terminal = Config::preset(Phase::Terminal);
    let id = |cfg: &Config, locked| ConfigId {
        crc32: config_fingerprint(cfg),
        locked,
    };
    // Boots unlocked with the default configuration.
    let st = fw.status().unwrap();
    assert_eq!(st.protocol_version, PROTOCOL_VERSION);
    assert_eq!(st.config, id(&Config::default(), false));
    // The bounds hold over the wire too.
    let evil = Config {
        pfa: 1e-300,
        ..Config::default()
    };
    assert!(matches!(
        fw.try_configure(&evil).unwrap(),
        Err(WireError::OutOfRange { ref field, value, .. }) if field.as_str() == "pfa" && value == 1e-300
    ));
    fw.configure(&terminal).unwrap();
    assert_eq!(fw.last_config(), Some(id(&terminal, false)));
    fw.lock().unwrap();
    assert_eq!(fw.last_config(), Some(id(&terminal, true)));
    // Refused, with the fingerprint of the configuration that stays.
    for cfg in [Config::default(), terminal, evil] {
        assert_eq!(
            fw.try_configure(&cfg).unwrap(),
            Err(WireError::Locked {
                config_crc32: config_fingerprint(&terminal)
            })
        );
    }
    // Epochs run under the locked configuration, bit for bit the host's.
    for (time_s, sats, apriori) in range_vectors(3).iter().take(3) {
        let epoch = Epoch::ranges(*time_s, sats, *apriori);
        let p = fw.process(&epoch).unwrap();
        assert_eq!(fw.last_config(), Some(id(&terminal, true)));
        let want = host_result(&terminal, &epoch).map(|r| wire_bytes(&r));
        assert_eq!(
            p.outcome.map(|r| wire_bytes(&r)).map_err(|_| ()),
            want.map_err(|_| ())
        );
    }
    let st = fw.status().unwrap();
    assert_eq!(st.config, id(&terminal, true));
}
