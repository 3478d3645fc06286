//! How fast bytes and frames reach the firmware through QEMU's UART models.
//! 1. Delimiters (ignored by the firmware) then a status request, timed:
//!    the raw byte rate into the link UART.
//! 2. Frames streamed back to back without waiting for answers
//!    (the firmware receives by interrupt into its ring), every answer
//!    collected and checked in order: `Status` requests (smallest frames),
//!    and linearised 8-satellite epochs; per machine (mps2-an386 and the
//!    STM32F4 build under netduinoplus2). Rates are of the whole exchange:
//!    from the first byte sent to the last answer received.
//!
//! `cargo run --release -p host-tests --example qemu_throughput`
use std::time::Instant;

use raim_core::{LinearObservation, SatId, System};
use raim_proto::message::{CommandRef, ResponseBody};
use raim_qemu::{Machine, Options, QemuSession, ANSWER_TIMEOUT};

fn sky() -> Vec<LinearObservation> {
    (0..8)
        .map(|i| {
            let (az, el) = (i as f64 * 45.0, 15.0 + (i as f64 * 23.0) % 70.0);
            let mut o = LinearObservation::from_az_el(
                SatId::new(System::Gps, i as u8 + 1),
                az.to_radians(),
                el.to_radians(),
                0.1 * i as f64 - 0.3,
            );
            o.sigma_m = Some(1.0);
            o
        })
        .collect()
}

fn stream(fw: &mut QemuSession, n: usize, epochs: bool) -> anyhow::Result<()> {
    let sats = sky();
    let mut bytes = Vec::new();
    let mut first = None;
    for k in 0..n {
        let command = if epochs {
            CommandRef::Linear {
                time_s: k as f64,
                sats: &sats,
            }
        } else {
            CommandRef::Status
        };
        let (seq, f) = fw.frame(command)?;
        first.get_or_insert(seq);
        bytes.extend(f);
    }
    let first = first.unwrap_or(0);
    let t = Instant::now();
    fw.send_raw(&bytes)?;
    let mut answered = 0usize;
    for k in 0..n {
        let r = fw.recv(ANSWER_TIMEOUT)?;
        anyhow::ensure!(r.seq == Some(first + k as u32), "answer {k}: {:?}", r.seq);
        anyhow::ensure!(
            matches!(r.body, ResponseBody::Status(_) | ResponseBody::Result(_)),
            "answer {k}: {:?}",
            r.body
        );
        let mut buf = [0u8; 4096];
        answered += postcard::to_slice(&r, &mut buf).map_or(0, |v| v.len());
    }
    let s = t.elapsed().as_secs_f64();
    let st = fw.status()?;
    println!(
        "  {n} {} frames ({} bytes in, ~{answered} payload bytes out) in {s:.2} s: {:.0} frames/s, {:.0} bytes/s in; overruns {}, ring full {}",
        if epochs { "epoch" } else { "Status" },
        bytes.len(),
        n as f64 / s,
        bytes.len() as f64 / s,
        st.uart_overruns,
        st.rx_ring_overflows
    );
    Ok(())
}

fn main() -> anyhow::Result<()> {
    for machine in Machine::ALL {
        let elf = raim_qemu::firmware_elf_for(machine)?;
        let mut fw = QemuSession::start_with(
            &elf,
            &Options {
                machine,
                ..Options::default()
            },
        )?;
        println!("{}:", machine.qemu_name());
        fw.status()?;
        for n in [20_000usize, 100_000] {
            let t = Instant::now();
            fw.send_raw(&vec![0u8; n])?;
            fw.status()?;
            let s = t.elapsed().as_secs_f64();
            println!("  {n} delimiters in {s:.2} s: {:.0} bytes/s", n as f64 / s);
        }
        stream(&mut fw, 1000, false)?;
        stream(&mut fw, 1000, true)?;
    }
    Ok(())
}
