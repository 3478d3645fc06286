//! `raim provision`: the installation step of the configuration authority
//! (docs/PROTOCOL.md "Configuration authority"). Seals a unit configuration
//! (TOML, the serde form of `raim_proto::UnitConfig`) into the
//! `.raim_config` section of a copy of the firmware image, with the unit's
//! key written into `.raim_key` when one is given: the seal is then the
//! key's HMAC, otherwise SHA-256. Program the result with probe-rs
//! (`probe-rs download --chip STM32F407VGTx IMAGE`) or run it under QEMU.

use std::path::PathBuf;

use anyhow::{anyhow, bail, Context, Result};
use raim_proto::unit::{Hex, UnitConfig, PROVISION_BYTES};

/// The arguments of `raim provision`.
#[derive(clap::Args)]
pub struct ProvisionArgs {
    /// The unit configuration, TOML (keys: snapshot, araim, pf, host_sigmas;
    /// docs/PROTOCOL.md "Configuration authority").
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

/// Runs `raim provision`; prints the configuration's fingerprint.
pub fn run(a: &ProvisionArgs) -> Result<()> {
    let text = std::fs::read_to_string(&a.config)
        .with_context(|| format!("reading the unit configuration {}", a.config.display()))?;
    let unit: UnitConfig = toml::from_str(&text)
        .with_context(|| format!("{}: not a unit configuration", a.config.display()))?;
    if let Some(c) = &unit.snapshot {
        c.validate()
            .map_err(|e| anyhow!("{}: snapshot: {e}", a.config.display()))?;
    }
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

    /// The TOML form round-trips a unit configuration.
    #[test]
    fn toml_round_trips() {
        let u = UnitConfig {
            snapshot: Some(raim_core::Config::preset(raim_core::Phase::Terminal)),
            araim: None,
            pf: None,
            host_sigmas: false,
        };
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
