//! A corrupt RINEX file never crashes the host. A RINEX 2
//! observation file whose third epoch has month 13 (tests/data/month13.05o,
//! synthetic) is refused with a typed error naming the line; the same file
//! without the corruption (month13_control.05o) loads.

use std::path::PathBuf;

use raim_gnss::error::GnssError;
use raim_gnss::rinex_io::ObsData;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

#[test]
fn control_file_loads() {
    let d = ObsData::load(&data("month13_control.05o")).unwrap();
    assert_eq!(d.epochs.len(), 4);
    assert_eq!(d.epochs[0].sats.len(), 4);
}

/// Verifies: TOOL-RINEX
#[test]
fn month_13_is_a_typed_error_naming_the_line() {
    let err = ObsData::load(&data("month13.05o")).unwrap_err();
    match err {
        GnssError::BadEpoch {
            line, ref detail, ..
        } => {
            // Header 14 lines, two epochs of 5 lines: the third epoch
            // record is line 25.
            assert_eq!(line, 25, "{err}");
            assert!(detail.contains("month 13"), "{err}");
        }
        other => panic!("{other}"),
    }
}

/// The cause (docs/RINEX_GUARD.md): the `rinex` crate alone panics on this
/// file, inside hifitime's `Epoch::from_gregorian_*` ("invalid Gregorian
/// date"), which rinex 0.24 `epoch::parse_in_timescale` calls instead of
/// the fallible `maybe_from_gregorian_*`. When upstream fixes it, this test
/// fails: update the note then (the guard stays, as defence in depth).
#[test]
fn the_rinex_crate_alone_panics_on_month_13() {
    let path = data("month13.05o");
    let caught = std::panic::catch_unwind(|| {
        let r = raim_gnss::rinex_io::open(&path);
        if let Ok(r) = r {
            r.observations_iter().count()
        } else {
            0
        }
    });
    let payload = caught.expect_err("rinex 0.24 no longer panics on month 13");
    let msg = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_default();
    assert!(msg.contains("invalid Gregorian date"), "{msg}");
}
