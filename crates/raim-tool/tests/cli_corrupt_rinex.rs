//! A corrupt RINEX file never crashes the `raim` tool. A RINEX 2
//! observation file whose third epoch has month 13 (raim-gnss's test file)
//! is refused with an error naming the file and the line, a failure exit
//! status, and no panic (the `rinex` crate alone panics on it:
//! docs/RINEX_GUARD.md).

use std::process::Command;

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data");
const CORRUPT: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../raim-gnss/tests/data/month13.05o"
);

/// Verifies: TOOL-RINEX
#[test]
fn month_13_is_an_error_naming_the_line_not_a_panic() {
    let out = Command::new(env!("CARGO_BIN_EXE_raim"))
        .args([
            "replay",
            "--obs",
            CORRUPT,
            "--nav",
            &format!("{DATA}/07590920.05n"),
            "--systems",
            "G",
        ])
        .output()
        .expect("spawn raim");
    let err = String::from_utf8(out.stderr).expect("utf8");
    assert!(!out.status.success(), "{err}");
    // A panic exits with 101 and prints "panicked at".
    assert_ne!(out.status.code(), Some(101), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.contains("month13.05o:25"), "{err}");
    assert!(err.contains("month 13 outside 1..=12"), "{err}");
}
