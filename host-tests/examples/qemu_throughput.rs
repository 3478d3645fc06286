//! How fast bytes reach the firmware through QEMU's UART model: sends
//! delimiters (ignored by the firmware) and a status request, and times it.
//! `cargo run --release -p host-tests --example qemu_throughput`
use std::time::{Duration, Instant};

fn main() -> anyhow::Result<()> {
    let elf = raim_qemu::firmware_elf()?;
    let mut fw = raim_qemu::QemuSession::start(&elf)?;
    fw.status()?;
    for n in [20_000usize, 100_000] {
        let t = Instant::now();
        fw.send_raw(&vec![0u8; n])?;
        fw.status()?;
        let s = t.elapsed().as_secs_f64();
        println!("{n} bytes in {s:.2} s: {:.0} bytes/s", n as f64 / s);
    }
    let _ = Duration::ZERO;
    Ok(())
}
