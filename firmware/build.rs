//! The one place of the firmware's link arguments. The memory layout is a
//! top-level file of the repository (`../memory.x` for QEMU's mps2-an386,
//! `../memory-stm32f4.x` for the real board); it is copied into OUT_DIR as
//! `memory.x`, where cortex-m-rt's `link.x` finds it. There is deliberately
//! no `firmware/memory.x`: it would shadow the top-level one.
use std::path::PathBuf;

fn main() {
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("OUT_DIR"));
    let stm32f4 = std::env::var_os("CARGO_FEATURE_BOARD_STM32F4").is_some();
    let layout = if stm32f4 {
        "../memory-stm32f4.x"
    } else {
        "../memory.x"
    };
    let mut text =
        std::fs::read_to_string(layout).unwrap_or_else(|e| panic!("reading {layout}: {e}"));
    if stm32f4 && std::env::var_os("CARGO_FEATURE_QEMU_NETDUINOPLUS2").is_some() {
        // QEMU's netduinoplus2 maps 192 KiB of SRAM at 0x20000000 and no
        // CCM: the CCM region's 64 KiB go above the part's 128 KiB of SRAM.
        let (hw, qemu) = (
            "CCMRAM : ORIGIN = 0x10000000, LENGTH = 64K",
            "CCMRAM : ORIGIN = 0x20020000, LENGTH = 64K",
        );
        assert_eq!(text.matches(hw).count(), 1, "{layout}: one `{hw}`");
        text = text.replace(hw, qemu);
    }
    std::fs::write(out.join("memory.x"), text).unwrap_or_else(|e| panic!("memory.x: {e}"));
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
    link_idle(out);
}

/// Bounds of the test-only link pause, s: it may only lengthen the unit's
/// 0.25 s (`raim_server::LINK_IDLE_S`), and stays below a minute so that a
/// frame a test cuts on purpose still ends before the test's own deadline.
const TEST_LINK_IDLE_S: std::ops::RangeInclusive<u32> = 1..=60;

/// `OUT_DIR/link_idle.rs`: the pause on the link that ends a frame. It is
/// `raim_server::LINK_IDLE_S` unless the test-only setting
/// `RAIM_TEST_LINK_IDLE_S` (whole seconds, bounded above) is given: under
/// QEMU without `-icount` the guest's clock is the host's, so a host that
/// does not run QEMU for 0.25 s between two bytes of one frame cuts the
/// frame (docs/EVIDENCE.md "The suite under load"); the streaming tests
/// run a build with a pause no scheduling stall reaches. A value out of
/// bounds fails the build.
fn link_idle(out: &std::path::Path) {
    println!("cargo:rerun-if-env-changed=RAIM_TEST_LINK_IDLE_S");
    let value = match std::env::var("RAIM_TEST_LINK_IDLE_S") {
        Ok(v) => {
            let s: u32 = v
                .trim()
                .parse()
                .unwrap_or_else(|e| panic!("RAIM_TEST_LINK_IDLE_S={v:?}: {e}"));
            assert!(
                TEST_LINK_IDLE_S.contains(&s),
                "RAIM_TEST_LINK_IDLE_S={s} s is outside {TEST_LINK_IDLE_S:?} s"
            );
            format!("{s}.0")
        }
        Err(_) => "raim_server::LINK_IDLE_S".into(),
    };
    let text = format!(
        "/// The pause on the link that ends a frame, s: `raim_server::LINK_IDLE_S`,\n\
         /// or the test-only build setting `RAIM_TEST_LINK_IDLE_S` (build.rs).\n\
         pub const LINK_IDLE_S: f64 = {value};\n"
    );
    std::fs::write(out.join("link_idle.rs"), text).unwrap_or_else(|e| panic!("link_idle.rs: {e}"));
}
