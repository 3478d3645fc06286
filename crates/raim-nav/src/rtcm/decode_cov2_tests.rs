//! Decoder paths neither GMSD7 nor the first coverage tests reach (issue
//! 37, structural coverage, second pass): every MSM signal ID of the five
//! systems against the RTCM 10403.3 tables, a message that is no
//! Keplerian ephemeris, and the GLONASS health bits of a 1020.

use super::*;
use std::string::String;
use std::vec::Vec;

/// RTCM 10403.3 MSM signal IDs 1..=32 as RINEX band and attribute ("" for
/// a reserved ID), Tables 3.5-91 (GPS), 3.5-96 (GLONASS), 3.5-99
/// (Galileo), 3.5-105 (QZSS) and 3.5-108 (BeiDou, with B2a and B1C), as
/// RTKLIB tabulates them (src/rtcm3.c, `msm_sig_gps` ... `msm_sig_cmp`,
/// the demo5 branch's BeiDou row).
const GPS: [&str; 32] = [
    "", "1C", "1P", "1W", "", "", "", "2C", "2P", "2W", "", "", "", "", "2S", "2L", "2X", "", "",
    "", "", "5I", "5Q", "5X", "", "", "", "", "", "1S", "1L", "1X",
];
const GLONASS: [&str; 32] = [
    "", "1C", "1P", "", "", "", "", "2C", "2P", "", "", "", "", "", "", "", "", "", "", "", "", "",
    "", "", "", "", "", "", "", "", "", "",
];
const GALILEO: [&str; 32] = [
    "", "1C", "1A", "1B", "1X", "1Z", "", "6C", "6A", "6B", "6X", "6Z", "", "7I", "7Q", "7X", "",
    "8I", "8Q", "8X", "", "5I", "5Q", "5X", "", "", "", "", "", "", "", "",
];
const QZSS: [&str; 32] = [
    "", "1C", "", "", "", "", "", "", "6S", "6L", "6X", "", "", "", "2S", "2L", "2X", "", "", "",
    "", "5I", "5Q", "5X", "", "", "", "", "", "1S", "1L", "1X",
];
const BEIDOU: [&str; 32] = [
    "", "2I", "2Q", "2X", "", "", "", "6I", "6Q", "6X", "", "", "", "7I", "7Q", "7X", "", "", "",
    "", "", "5D", "5P", "5X", "7D", "", "", "", "", "1D", "1P", "1X",
];

/// The decoder's band and attribute of a signal ID, as RINEX writes them.
fn code(sig: Option<(u8, u8)>) -> String {
    sig.map(|(band, attr)| std::format!("{band}{}", attr as char))
        .unwrap_or_default()
}

/// A system's signal-ID decoder.
type SignalOf = fn(u8) -> Option<(u8, u8)>;

/// Every signal ID 1..=32 of each system decodes to the table's band and
/// attribute, a reserved one to none; 0 and 33 are outside the 32-bit
/// signal mask.
///
/// Verifies: RX-DECODE
#[test]
fn msm_signal_ids_match_the_rtcm_tables() {
    let systems: [(&str, SignalOf, &[&str; 32]); 5] = [
        ("GPS", gps_signal, &GPS),
        ("GLONASS", glonass_signal, &GLONASS),
        ("Galileo", galileo_signal, &GALILEO),
        ("QZSS", qzss_signal, &QZSS),
        ("BeiDou", beidou_signal, &BEIDOU),
    ];
    for (name, decode, table) in systems {
        for (k, want) in table.iter().enumerate() {
            let id = k as u8 + 1;
            assert_eq!(code(decode(id)), *want, "{name} signal ID {id}");
        }
        assert_eq!(decode(0), None, "{name}");
        assert_eq!(decode(33), None, "{name}");
    }
}

/// A payload of another message given to the Keplerian decoder (the
/// store's decode on use) is `NotKepler` with its number, and says so.
#[test]
fn a_message_that_is_no_keplerian_ephemeris_is_refused_by_number() {
    // DF002 = 1077 in the first 12 bits, then zeros.
    let payload = [(1077u16 >> 4) as u8, ((1077u16 & 0x0F) << 4) as u8, 0, 0];
    let e = kepler_message(&payload).unwrap_err();
    assert!(
        matches!(e, DecodeError::NotKepler { message: 1077 }),
        "{e:?}"
    );
    assert_eq!(
        std::format!("{e}"),
        "1077 is not a Keplerian ephemeris message"
    );
}

/// GMSD7's 1020 payloads.
fn gmsd7_1020s() -> Vec<Vec<u8>> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/GMSD7_20121014.rtcm3"
    );
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let mut out = Vec::new();
    let mut i = 0;
    while i + 6 <= bytes.len() {
        if bytes[i] != 0xD3 {
            i += 1;
            continue;
        }
        let len = (usize::from(bytes[i + 1] & 0x03) << 8) | usize::from(bytes[i + 2]);
        let Some(f) = bytes.get(i..i + 6 + len) else {
            break;
        };
        let p = &f[3..3 + len];
        if len >= 2 && (u16::from(p[0]) << 4 | u16::from(p[1]) >> 4) == 1020 {
            out.push(p.to_vec());
        }
        i += 6 + len;
    }
    out
}

/// Payload bit `bit` (0 = the most significant of the first byte) set.
fn with_bit(p: &[u8], bit: usize) -> Vec<u8> {
    let mut q = p.to_vec();
    q[bit / 8] |= 0x80 >> (bit % 8);
    q
}

/// The GLONASS ICD's health flags, read from a 1020 (RTCM 10403.3
/// §3.5.12): the MSB of B_n (DF108) and l_n of the third string (DF123)
/// each mark the satellite unhealthy. DF108 is payload bit 39 (DF002 12,
/// DF038 6, DF040 5, DF104 1, DF105 1, DF106 2, DF107 12), DF123 bit 230
/// (then DF109 1, DF110 7, three times velocity 24, position 27 and
/// acceleration 5, DF120 1, DF121 11, DF122 2).
///
/// Verifies: RX-DECODE
#[test]
fn either_glonass_health_bit_marks_a_1020_unhealthy() {
    let all = gmsd7_1020s();
    assert!(!all.is_empty());
    let mut healthy = 0;
    for p in &all {
        let (f, tb) = msg1020(p).unwrap();
        if f.unhealthy {
            continue;
        }
        healthy += 1;
        for bit in [39, 230] {
            let (g, tb2) = msg1020(&with_bit(p, bit)).unwrap();
            assert!(g.unhealthy, "bit {bit}");
            assert_eq!(
                (g.slot, g.x_km, g.tau_n_s, tb2),
                (f.slot, f.x_km, f.tau_n_s, tb)
            );
        }
    }
    assert!(healthy > 0, "GMSD7 has healthy GLONASS ephemerides");
}
