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
    println!("cargo:rustc-link-arg=--nmagic");
    println!("cargo:rustc-link-arg=-Tlink.x");
    println!("cargo:rustc-link-arg=-Tdefmt.x");
}
