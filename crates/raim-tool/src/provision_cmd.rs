//! `raim provision`: the installation step of the configuration authority
//! (docs/PROTOCOL.md "Configuration authority"). Seals a unit configuration
//! (TOML, the serde form of `raim_proto::UnitConfig`) into the
//! `.raim_config` section of a copy of the firmware image, with the unit's
//! key written into `.raim_key` when one is given: the seal is then the
//! key's HMAC, otherwise SHA-256. Program the result with probe-rs
//! (`probe-rs download --chip STM32F407VGTx IMAGE`) or run it under QEMU.
//!
//! Before anything is written, every part of the configuration passes the
//! unit's own boot validation (`raim_server::check_unit`, the code
//! `Server::boot` runs): a part that boot would refuse is refused here,
//! with the part and its typed error, not found in the aircraft (issue
//! 35). The checks are those of a unit with every engine (the QEMU board's
//! build); a build without ARAIM or with fewer PF engines (the STM32F4's
//! GA-PF 100) also refuses at boot a part its engines cannot run.

use std::path::PathBuf;

use anyhow::{anyhow, bail, Context, Result};
use raim_proto::unit::{Hex, UnitConfig, PROVISION_BYTES};

/// The arguments of `raim provision`.
#[derive(clap::Args)]
pub struct ProvisionArgs {
    /// The unit configuration, TOML (keys: snapshot, araim, pf, host_sigmas,
    /// model_check; docs/PROTOCOL.md "Configuration authority").
    #[arg(long, value_name = "FILE")]
    pub config: PathBuf,
    /// The unit's key, 64 hexadecimal digits; written into the image's
    /// .raim_key, and the seal is its HMAC. Without it the seal is SHA-256.
    #[arg(long, value_name = "HEX")]
    pub key: Option<String>,
    /// The provisioned image to write.
    #[arg(long, short, value_name = "FILE")]
    pub out: PathBuf,
    /// The firmware image (ELF) to provision.
    #[arg(value_name = "ELF")]
    pub elf: PathBuf,
}

fn parse_key(hex: &str) -> Result<[u8; 32]> {
    let hex = hex.trim();
    if hex.len() != 64 || !hex.bytes().all(|b| b.is_ascii_hexdigit()) {
        bail!(
            "--key: expected 64 hexadecimal digits, got {} characters",
            hex.len()
        );
    }
    let mut key = [0u8; 32];
    for (i, k) in key.iter_mut().enumerate() {
        *k = u8::from_str_radix(&hex[2 * i..2 * i + 2], 16).map_err(|e| anyhow!("--key: {e}"))?;
    }
    Ok(key)
}

/// The unit's boot validation of every part (`raim_server::check_unit`):
/// the part boot would refuse, named, with its typed error.
fn check(unit: &UnitConfig) -> Result<()> {
    raim_server::check_unit(unit).map_err(|r| {
        anyhow!(
            "{:?} part refused, as the unit's boot would refuse it: {}",
            r.part,
            r.error
        )
    })
}

/// Runs `raim provision`; prints the configuration's fingerprint.
pub fn run(a: &ProvisionArgs) -> Result<()> {
    let text = std::fs::read_to_string(&a.config)
        .with_context(|| format!("reading the unit configuration {}", a.config.display()))?;
    let unit: UnitConfig = toml::from_str(&text)
        .with_context(|| format!("{}: not a unit configuration", a.config.display()))?;
    check(&unit).with_context(|| format!("{}", a.config.display()))?;
    let key = a.key.as_deref().map(parse_key).transpose()?;
    let mut blob = [0u8; PROVISION_BYTES];
    raim_proto::unit::seal(&unit, key.as_ref(), &mut blob).map_err(|_| {
        anyhow!(
            "sealing {}: the configuration does not fit the {PROVISION_BYTES}-byte section",
            a.config.display()
        )
    })?;
    let staged = a.out.with_extension("staging");
    let mut image = a.elf.clone();
    if let Some(k) = key {
        std::fs::copy(&a.elf, &staged).with_context(|| format!("copying {}", a.elf.display()))?;
        image = raim_qemu::write_section(&staged, ".raim_key", &k, "keyed")?;
    }
    let sealed = raim_qemu::write_section(&image, ".raim_config", &blob, "sealed")?;
    std::fs::rename(&sealed, &a.out).with_context(|| format!("writing {}", a.out.display()))?;
    for f in [staged, image.clone()] {
        if f != a.elf {
            let _ = std::fs::remove_file(f);
        }
    }
    println!(
        "{}: fingerprint {} ({})",
        a.out.display(),
        Hex(&unit.fingerprint()),
        if key.is_some() {
            "HMAC seal"
        } else {
            "SHA-256 seal"
        }
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_are_64_hex_digits() {
        assert_eq!(parse_key(&"0f".repeat(32)).unwrap(), [0x0f; 32]);
        assert!(parse_key("00").is_err());
        assert!(parse_key(&"zz".repeat(32)).is_err());
    }

    /// A unit with every part valid: the terminal preset, a 10-satellite
    /// GPS + Galileo ISM (the ADD's entries), the seed's GA-PF at 100
    /// particles.
    fn full_unit() -> UnitConfig {
        use raim_core::{SatId, System};
        use raim_proto::araim_msg::{IsmFrame, IsmSat, WireAraimConfig};
        use raim_proto::message::SatList;
        let items: heapless::Vec<IsmSat, { raim_proto::CAPACITY }> = (0..10u8)
            .map(|i| IsmSat {
                id: SatId::new(if i < 5 { System::Gps } else { System::Galileo }, i % 5 + 1),
                sigma_ura_m: 0.75,
                sigma_ure_m: 0.5,
                b_nom_m: 0.5,
                p_sat: 1e-5,
            })
            .collect();
        let mut p_const = [None; raim_core::measurement::MAX_SYSTEMS];
        p_const[System::Gps.index()] = Some(1e-4);
        p_const[System::Galileo.index()] = Some(1e-4);
        UnitConfig {
            snapshot: Some(raim_core::Config::preset(raim_core::Phase::Terminal)),
            araim: Some(IsmFrame {
                config: WireAraimConfig::default(),
                p_const,
                sats: SatList {
                    declared: items.len() as u32,
                    items,
                },
            }),
            pf: Some(raim_proto::pf_msg::WirePfConfig::gapf(100, 7)),
            host_sigmas: false,
            model_check: raim_proto::WireModelCheckConfig {
                spacing_s: 900.0,
                window: 4,
                p_fa_per_hour: 1e-5,
            },
        }
    }

    /// What the unit's boot makes of `unit`: the provisioning error it
    /// reports (the host's server runs the firmware's boot code).
    fn boot_refusal(unit: &UnitConfig) -> Option<raim_proto::unit::ProvisionError> {
        let mut server = std::boxed::Box::new(raim_server::Server::new());
        // The GA-PF at 100 particles, as the STM32F4 board attaches it.
        let ga100: &'static mut raim_server::Ga100Engine =
            Box::leak(Box::new(raim_server::Ga100Engine::new(0)));
        server.attach_pf(raim_server::PfEngines {
            ga100: Some(ga100),
            ..raim_server::PfEngines::NONE
        });
        let entropy = raim_proto::auth::BootEntropy {
            bytes: [0; 32],
            hardware: false,
        };
        server.boot(Ok(Some(unit.clone())), 0, &entropy);
        server.status().provision_error
    }

    /// Issue 35: `raim provision` refuses what boot would refuse, for
    /// every part, with the same part and the part's own typed error: an
    /// invalid ARAIM part (P_sat 0; an ISM with no entry), an invalid
    /// PF part (window 0; a particle count not compiled in) and model-check
    /// settings out of their bounds (window 0 and 17, spacing NaN and
    /// 1e-4 s, P_h 0.9), each refused
    /// before anything is written, and refused by boot as `InvalidPart`
    /// of that part; the valid unit passes both.
    ///
    /// Verifies: SAFE-PROVISION, WIRE-Araim, MODEL-CONFIG
    #[test]
    fn provisioning_refuses_every_part_boot_refuses() {
        use raim_proto::araim_msg::AraimWireError;
        use raim_proto::error::WireError;
        use raim_proto::unit::{ProvisionError, UnitPart};
        let good = full_unit();
        check(&good).unwrap();
        assert_eq!(boot_refusal(&good), None);
        let mut bad_ism = good.clone();
        if let Some(i) = bad_ism.araim.as_mut() {
            i.sats.items[3].p_sat = 0.0;
        }
        let mut empty_ism = good.clone();
        if let Some(i) = empty_ism.araim.as_mut() {
            i.sats.items.clear();
            i.sats.declared = 0;
        }
        let mut bad_pf = good.clone();
        if let Some(p) = bad_pf.pf.as_mut() {
            p.config.window = 0;
        }
        let mut odd_particles = good.clone();
        if let Some(p) = odd_particles.pf.as_mut() {
            p.particles = 123;
        }
        let model = |f: &dyn Fn(&mut raim_proto::WireModelCheckConfig)| {
            let mut u = good.clone();
            f(&mut u.model_check);
            u
        };
        let window_0 = model(&|m| m.window = 0);
        let window_17 = model(&|m| m.window = 17);
        let spacing_nan = model(&|m| m.spacing_s = f64::NAN);
        let spacing_tiny = model(&|m| m.spacing_s = 1e-4);
        let p_h_large = model(&|m| m.p_fa_per_hour = 0.9);
        let cases = [
            (&bad_ism, UnitPart::Araim, "p_sat"),
            (&empty_ism, UnitPart::Araim, "no satellite entry"),
            (&bad_pf, UnitPart::Pf, "window"),
            (&odd_particles, UnitPart::Pf, "123"),
            (
                &window_0,
                UnitPart::ModelCheck,
                "window = 0 outside [1, 16]",
            ),
            (
                &window_17,
                UnitPart::ModelCheck,
                "window = 17 outside [1, 16]",
            ),
            (&spacing_nan, UnitPart::ModelCheck, "non-finite spacing_s"),
            (&spacing_tiny, UnitPart::ModelCheck, "spacing_s = 0.0001"),
            (&p_h_large, UnitPart::ModelCheck, "p_fa_per_hour = 0.9"),
        ];
        for (unit, part, detail) in cases {
            let r = raim_server::check_unit(unit).unwrap_err();
            assert_eq!(r.part, part);
            let msg = check(unit).unwrap_err().to_string();
            assert!(msg.contains(&format!("{part:?} part refused")), "{msg}");
            assert!(msg.contains(detail), "{msg}");
            assert_eq!(boot_refusal(unit), Some(ProvisionError::InvalidPart(part)));
        }
        assert_eq!(
            raim_server::check_unit(&empty_ism).unwrap_err().error,
            WireError::Araim(AraimWireError::EmptyIsm)
        );
        // The model check's refusal is the one a runtime `ModelCheck` gets.
        assert_eq!(
            raim_server::check_unit(&window_17).unwrap_err().error,
            window_17.model_check.check().unwrap_err()
        );
    }

    /// `raim provision` stops at the check: with an invalid PF part it
    /// names the file and the part, and writes no image (the ELF is never
    /// read: here it does not exist).
    ///
    /// Verifies: SAFE-PROVISION
    #[test]
    fn run_refuses_before_writing_anything() {
        let dir = std::env::temp_dir().join(format!("raim-provision-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // No ARAIM part: its P_const (`None` for the constellations not
        // in use) has no TOML form.
        let mut unit = UnitConfig {
            araim: None,
            ..full_unit()
        };
        if let Some(p) = unit.pf.as_mut() {
            p.config.window = 0;
        }
        let config = dir.join("unit.toml");
        std::fs::write(&config, toml::to_string(&unit).unwrap()).unwrap();
        let out = dir.join("sealed.elf");
        let e = run(&ProvisionArgs {
            config: config.clone(),
            key: None,
            out: out.clone(),
            elf: dir.join("no-such-firmware.elf"),
        })
        .unwrap_err();
        let msg = format!("{e:#}");
        assert!(
            msg.contains("unit.toml") && msg.contains("Pf part refused"),
            "{msg}"
        );
        assert!(!out.exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The TOML form round-trips a unit configuration; a file without the
    /// model check's table, or with only some of its fields, gets the
    /// defaults for the rest (the check as it ran before the settings
    /// existed), and the fingerprint covers every one of them.
    ///
    /// Verifies: MODEL-CONFIG
    #[test]
    fn toml_round_trips() {
        let u = UnitConfig {
            snapshot: Some(raim_core::Config::preset(raim_core::Phase::Terminal)),
            araim: None,
            pf: None,
            host_sigmas: false,
            model_check: raim_proto::WireModelCheckConfig::DEFAULT,
        };
        let bare: UnitConfig = toml::from_str("host_sigmas = false").unwrap();
        assert_eq!(bare.model_check, raim_proto::WireModelCheckConfig::DEFAULT);
        let partial: UnitConfig =
            toml::from_str("host_sigmas = false\n[model_check]\nwindow = 4\n").unwrap();
        assert_eq!(
            partial.model_check,
            raim_proto::WireModelCheckConfig {
                window: 4,
                ..raim_proto::WireModelCheckConfig::DEFAULT
            }
        );
        assert_ne!(partial.fingerprint(), bare.fingerprint());
        let text = toml::to_string(&u).unwrap();
        let back: UnitConfig = toml::from_str(&text).unwrap();
        assert_eq!(back, u);
        // docs/unit.toml is this configuration, written by this test
        // (`RAIM_WRITE_DOCS=1`): the example of docs/PROTOCOL.md.
        let doc = concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/unit.toml");
        if std::env::var_os("RAIM_WRITE_DOCS").is_some() {
            std::fs::write(doc, &text).unwrap();
        }
        assert_eq!(std::fs::read_to_string(doc).unwrap(), text);
    }
}
