//! The one place of the firmware's link arguments. The memory layout is a
//! top-level file of the repository (`../memory.x` for QEMU's mps2-an386,
//! `../memory-stm32f4.x` for the real board); it is copied into OUT_DIR as
//! `memory.x`, where cortex-m-rt's `link.x` finds it. There is deliberately
//! no `firmware/memory.x`: it would shadow the top-level one.
use std::path::PathBuf;

fn main() {
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("OUT_DIR"));
    let layout = if std::env::var_os("CARGO_FEATURE_BOARD_STM32F4").is_some() {
        "../memory-stm32f4.x"
    } else {
        "../memory.x"
    };
    std::fs::copy(layout, out.join("memory.x")).unwrap_or_else(|e| panic!("copying {layout}: {e}"));
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed={layout}");
    println!("cargo:rerun-if-changed=build.rs");
    settings(&out);
    println!("cargo:rustc-link-arg=--nmagic");
    println!("cargo:rustc-link-arg=-Tlink.x");
    println!("cargo:rustc-link-arg=-Tdefmt.x");
}

/// Bounds of the integrity-alarm output's time-to-alert, s: TSO-C129a's
/// RAIM alerts within 30 s en route and 10 s in terminal and non-precision
/// approach; below 1 s the output would chatter between epochs at 1 Hz.
const TIME_TO_ALERT_S: std::ops::RangeInclusive<u32> = 1..=30;

/// Build settings of the unit (docs/SAFETY.md), written to
/// `OUT_DIR/settings.rs`: `RAIM_TIME_TO_ALERT_S` (default 10). A value out
/// of bounds fails the build.
fn settings(out: &std::path::Path) {
    println!("cargo:rerun-if-env-changed=RAIM_TIME_TO_ALERT_S");
    let tta: u32 = match std::env::var("RAIM_TIME_TO_ALERT_S") {
        Ok(v) => v
            .trim()
            .parse()
            .unwrap_or_else(|e| panic!("RAIM_TIME_TO_ALERT_S={v:?}: {e}")),
        Err(_) => 10,
    };
    assert!(
        TIME_TO_ALERT_S.contains(&tta),
        "RAIM_TIME_TO_ALERT_S={tta} s is outside {TIME_TO_ALERT_S:?} s"
    );
    let text = format!(
        "/// The integrity-alarm output's time-to-alert, s (build setting\n\
         /// `RAIM_TIME_TO_ALERT_S`, bounded by build.rs).\n\
         pub const TIME_TO_ALERT_S: u32 = {tta};\n"
    );
    std::fs::write(out.join("settings.rs"), text).unwrap_or_else(|e| panic!("settings.rs: {e}"));
}
