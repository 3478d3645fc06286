//! The firmware's flash. The QEMU board's build without the
//! optional engines (`--no-default-features --features board-qemu`: the
//! snapshot monitor, MCUSUM, protocol, NMEA and safety code; no ARAIM, no
//! particle filter, no reconstruction FDE) stays within 128 KiB, read from
//! the ELF deterministically; the default (full) build's and the STM32F4
//! build's flash are printed for BENCHMARKS.md. The build without the
//! reconstruction FDE refuses a configuration that selects it with a typed
//! error and runs the sequential FDE bit for bit with the host.
//! docs/FLASH.md has the choices and numbers.
//!
//!     cargo test --release -p host-tests --test qemu_flash -- --nocapture

mod qemu_common;

use object::{Object, ObjectSection, ObjectSegment, SectionFlags, SectionKind};
use qemu_common::{host_result, range_vectors, wire_bytes};
use raim_core::{Config, Epoch, FdeMethod};
use raim_proto::WireError;
use std::path::Path;

/// The flash budget of the build without the optional engines, B, for its
/// code and constants: without the provisioned-configuration section and
/// without `.data`'s initial image (docs/FLASH.md: 128 KiB was the goal;
/// the configuration authority took it to 144 KiB, issue 35's fail-safe
/// link, timer and unit identity to 145 KiB, its boot counter to
/// 147 KiB, its model-check settings as a configuration part and the
/// counter's re-reads to 148 KiB).
const SNAPSHOT_FLASH_BUDGET_B: u64 = 148 * 1024;

/// The budget of the same build's `.data` initial image, B: the device
/// server, a `const`-initialised static (40,372 B measured, docs/FLASH.md
/// "The server's initial image"), with room for the link's small statics.
const SNAPSHOT_DATA_IMAGE_BUDGET_B: u64 = 42 * 1024;

/// The NMEA writer of the snapshot build: no geoid, no GSV or DOPs (the
/// firmware's features `geoid` and `nmea-sky` are off there).
const SNAPSHOT_NMEA: raim_proto::nmea::Options = raim_proto::nmea::Options {
    geoid: false,
    sky: false,
};

/// ELF section flag: occupies memory at run time.
const SHF_ALLOC: u64 = 0x2;

/// The sections a build burns into flash (allocated, with contents: the
/// vector table, code, constants, `.data`'s initial values, the key slot),
/// with their sizes, and their total. Checked against the loadable
/// segments' file sizes, the same bytes counted another way.
fn flash_sections(elf: &Path) -> (Vec<(String, u64)>, u64) {
    let data = std::fs::read(elf).unwrap_or_else(|e| panic!("{}: {e}", elf.display()));
    let file = object::File::parse(&*data).expect("an ELF file");
    let mut sections = Vec::new();
    for s in file.sections() {
        let alloc =
            matches!(s.flags(), SectionFlags::Elf { sh_flags } if sh_flags & SHF_ALLOC != 0);
        if alloc && s.kind() != SectionKind::UninitializedData && s.size() > 0 {
            sections.push((s.name().unwrap_or("?").to_string(), s.size()));
        }
    }
    let total: u64 = sections.iter().map(|(_, n)| n).sum();
    let loaded: u64 = file.segments().map(|s| s.file_range().1).sum();
    assert_eq!(
        total, loaded,
        "sections {sections:?} against the LOAD segments"
    );
    (sections, total)
}

fn report(name: &str, elf: &Path) -> u64 {
    let (sections, total) = flash_sections(elf);
    let parts: Vec<String> = sections.iter().map(|(n, s)| format!("{n} {s}")).collect();
    println!(
        "{name}: {} = {total} B ({:.1} KiB)",
        parts.join(" + "),
        total as f64 / 1024.0
    );
    total
}

/// Verifies: FW-FLASH
#[test]
fn snapshot_build_fits_128_kib_of_flash() {
    let snapshot = raim_qemu::firmware_elf_snapshot().expect("snapshot firmware build");
    let total = report("QEMU, no default features", &snapshot);
    // The provisioned-configuration section is the installation's data, in
    // a region of its own (on the STM32F4 a flash sector of its own), not
    // code: the 128 KiB bound is on everything else (docs/FLASH.md).
    let (sections, _) = flash_sections(&snapshot);
    let provision: u64 = sections
        .iter()
        .filter(|(n, _)| n == ".raim_config")
        .map(|(_, b)| b)
        .sum();
    assert_eq!(provision, raim_proto::unit::PROVISION_BYTES as u64);
    // `.data`'s initial values: the server's compile-time image (its
    // `const fn` constructor), copied to RAM before `main`; bounded on its
    // own, so that code growth is still caught by the first bound.
    let data_image: u64 = sections
        .iter()
        .filter(|(n, _)| n == ".data")
        .map(|(_, b)| b)
        .sum();
    let code = total - provision - data_image;
    println!(
        "without .raim_config: {} B; code and constants {code} B, .data image {data_image} B",
        total - provision
    );
    assert!(
        code <= SNAPSHOT_FLASH_BUDGET_B,
        "{code} B of flash > {SNAPSHOT_FLASH_BUDGET_B} B"
    );
    assert!(
        data_image <= SNAPSHOT_DATA_IMAGE_BUDGET_B,
        "{data_image} B of .data > {SNAPSHOT_DATA_IMAGE_BUDGET_B} B"
    );
    // Recorded, not bounded: the full QEMU build and the
    // STM32F4 build (both within their parts' flash: the linker checks).
    report(
        "QEMU, default features (araim, pf, multifault)",
        &raim_qemu::firmware_elf().expect("firmware build"),
    );
    report(
        "STM32F4 (araim at ram-192k, pf: GA-PF 100, multifault)",
        &raim_qemu::firmware_elf_for(raim_qemu::Machine::NetduinoPlus2)
            .expect("STM32F4 firmware build"),
    );
}

/// Without the reconstruction FDE, `FdeMethod::Reconstruction` is refused
/// over the wire (`t_max` outside [0, 0]), the configuration in force
/// stays, and epochs run the sequential FDE bit for bit with the host.
///
/// Verifies: FW-FLASH
#[test]
fn snapshot_build_refuses_the_reconstruction_fde() {
    let elf = raim_qemu::firmware_elf_snapshot().expect("snapshot firmware build");
    let mut fw = raim_qemu::QemuSession::start(&elf).expect("qemu-system-arm with the firmware");
    let multifault = Config {
        fde_method: FdeMethod::Reconstruction {
            t_max: 2,
            group_budget: 64,
        },
        ..Config::default()
    };
    assert_eq!(multifault.validate(), Ok(()), "the host build has it");
    let refused = fw.try_configure(&multifault).unwrap();
    assert!(
        matches!(
            refused,
            Err(WireError::OutOfRange { ref field, value, min, max })
                if field.as_str() == "t_max" && value == 2.0 && min == 0.0 && max == 0.0
        ),
        "{refused:?}"
    );
    let cfg = Config::default();
    let bench = raim_proto::UnitConfigRef {
        snapshot: Some(&cfg),
        araim: None,
        pf: None,
        host_sigmas: true,
        model_check: &raim_proto::WireModelCheckConfig::DEFAULT,
    };
    assert_eq!(fw.status().unwrap().config.fingerprint, bench.fingerprint());
    let mut faulted = 0;
    for (time_s, sats, apriori) in range_vectors(8).iter() {
        let epoch = Epoch::ranges(*time_s, sats, *apriori);
        let p = fw.process(&epoch).unwrap();
        let want = host_result(&cfg, &epoch);
        faulted += usize::from(matches!(&want, Ok(r) if !r.exclusions.is_empty()));
        // The NMEA sentences (integer formatting on both sides) too.
        if let Ok(r) = &want {
            let host_nmea: Vec<String> = raim_proto::nmea::epoch_sentences(
                r,
                &raim_proto::nmea::Sky::new(&epoch),
                SNAPSHOT_NMEA,
            )
            .unwrap()
            .iter()
            .map(|s| s.trim_end().to_string())
            .collect();
            assert_eq!(p.nmea, host_nmea, "epoch at {time_s} s");
        }
        assert_eq!(
            p.outcome.map(|r| wire_bytes(&r)),
            want.map(|r| wire_bytes(&r)).map_err(WireError::from),
            "epoch at {time_s} s"
        );
    }
    println!("{faulted} of the epochs had an exclusion");
}

/// Without the particle filter, every `PfConfigure` is answered
/// `PfUnavailable`, a valid one and one with a particle count that no
/// build has alike (the PF configuration checks are not linked into this
/// build), and the configuration in force is unchanged.
///
/// Verifies: WIRE-PfUnavailable, FW-FLASH
#[test]
fn snapshot_build_answers_pf_configure_unavailable() {
    use raim_proto::message::{CommandRef, ResponseBody};
    use raim_proto::pf_msg::WirePfConfig;
    let elf = raim_qemu::firmware_elf_snapshot().expect("snapshot firmware build");
    let mut fw = raim_qemu::QemuSession::start(&elf).expect("qemu-system-arm with the firmware");
    let before = fw.status().unwrap().config.fingerprint;
    for pf in [WirePfConfig::gapf(100, 7), WirePfConfig::gapf(301, 7)] {
        assert_eq!(
            fw.call(CommandRef::PfConfigure(&pf)).unwrap(),
            ResponseBody::Error(WireError::PfUnavailable),
            "{pf:?}"
        );
    }
    assert_eq!(fw.status().unwrap().config.fingerprint, before);
}
