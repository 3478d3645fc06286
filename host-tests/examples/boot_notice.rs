//! Prints the boot notice of a firmware image under QEMU (mps2-an386):
//! `cargo run --release -p host-tests --example boot_notice -- IMAGE`,
//! e.g. to check an image `raim provision` wrote.
fn main() -> anyhow::Result<()> {
    let elf = std::env::args()
        .nth(1)
        .ok_or_else(|| anyhow::anyhow!("usage: boot_notice IMAGE"))?;
    let fw = raim_qemu::QemuSession::start_with(
        std::path::Path::new(&elf),
        &raim_qemu::Options {
            raw: true,
            ..raim_qemu::Options::default()
        },
    )?;
    let b = fw
        .boots()
        .first()
        .ok_or_else(|| anyhow::anyhow!("no boot notice"))?;
    println!(
        "{:?} locked {} fingerprint {} provision error {:?} keyed {}",
        b.config.source,
        b.config.locked,
        raim_proto::unit::Hex(&b.config.fingerprint),
        b.provision_error,
        b.auth_provisioned
    );
    Ok(())
}
