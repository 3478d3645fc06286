//! Particle-filter RAIM cost per epoch (BENCHMARKS.md "Particle-filter
//! RAIM"): guest instructions per epoch under
//! `qemu -icount shift=0` (one instruction per virtual ns; SysTick at
//! mps2-an386's 25 MHz, so one tick is 40 instructions) and host wall-clock
//! time through the host's `Server` (the same code, f32 state), for the
//! GA-PF, the SIR PF and the EKF at 100 and 300 particles and 6 to 12 GPS
//! satellites. Each row: mean of epochs 2..=6 of one run (epoch 1 is the
//! first fix), clean data, seed 7.
//!
//! `cargo run --release -p host-tests --example qemu_pf_bench`

#[path = "../tests/qemu_common/mod.rs"]
mod qemu_common;

use std::time::Instant;

use qemu_common::{range_epoch, Rng};
use raim_core::pf::PfConfig;
use raim_core::{RangeObservation, System};
use raim_proto::message::{CommandRef, RequestRef, ResponseBody};
use raim_proto::{PfKind, WirePfConfig};
use raim_qemu::{Options, QemuSession};
use raim_server::{NoPlatform, PfEngines, Server};

const INSTRUCTIONS_PER_TICK: u64 = 40;
const EPOCHS: usize = 6;

struct Sink;
impl embedded_io::ErrorType for Sink {
    type Error = core::convert::Infallible;
}
impl embedded_io::Write for Sink {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        Ok(buf.len())
    }
    fn flush(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
}

fn host_send(server: &mut Server, seq: u32, command: CommandRef<'_>) {
    let mut scratch = vec![0u8; 4096];
    let mut out = vec![0u8; 4096];
    let frame = raim_proto::frame::encode(&RequestRef { seq, command }, &mut scratch, &mut out)
        .unwrap()
        .to_vec();
    for b in frame {
        server
            .on_byte(b, &mut Sink, &mut Sink, &mut NoPlatform)
            .unwrap();
    }
}

fn main() -> anyhow::Result<()> {
    let elf = raim_qemu::firmware_elf()?;
    let mut fw = QemuSession::start_with(
        &elf,
        &Options {
            icount: true,
            ..Options::default()
        },
    )?;
    fn leak<T>(t: T) -> Option<&'static mut T> {
        Some(Box::leak(Box::new(t)))
    }
    let mut host = Server::new();
    host.take_runtime_config(raim_core::Config::default())
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    host.attach_pf(PfEngines {
        ekf: leak(raim_core::pf::PfRaim::new(0)),
        pf100: leak(raim_core::pf::PfRaim::new(0)),
        pf300: leak(raim_core::pf::PfRaim::new(0)),
        ga100: leak(raim_core::pf::PfRaim::new(0)),
        ga300: leak(raim_core::pf::PfRaim::new(0)),
    });
    let mut host_seq = 0;
    println!("| filter | particles | satellites | guest instructions / epoch | M cycles at CPI 1.5 | fits 1 Hz at 168 MHz | host us / epoch |");
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    for (kind, particles) in [
        (PfKind::Ekf, 0),
        (PfKind::Pf, 100),
        (PfKind::Gapf, 100),
        (PfKind::Pf, 300),
        (PfKind::Gapf, 300),
    ] {
        for n in [6usize, 8, 10, 12] {
            let cfg = WirePfConfig {
                kind,
                particles,
                seed: 7,
                config: PfConfig {
                    sigma_m: 3.0,
                    ..PfConfig::default()
                },
            };
            let sky: Vec<(f64, f64)> = (0..n)
                .map(|i| (i as f64 * 360.0 / n as f64, 15.0 + (i as f64 * 23.0) % 70.0))
                .collect();
            let mut rng = Rng::new(n as u64);
            let epochs: Vec<Vec<RangeObservation>> = (0..EPOCHS)
                .map(|_| {
                    let mut e = range_epoch(&sky, &[System::Gps], &mut rng, &[]);
                    e.iter_mut().for_each(|o| o.sigma_m = None);
                    e
                })
                .collect();
            let seq = fw.send(CommandRef::PfConfigure(&cfg))?;
            let r = fw.recv(raim_qemu::ANSWER_TIMEOUT)?;
            anyhow::ensure!(
                r.seq == Some(seq) && r.body == ResponseBody::Configured,
                "{r:?}"
            );
            host_send(&mut host, host_seq, CommandRef::PfConfigure(&cfg));
            host_seq += 1;
            let (mut instr, mut host_s) = (0u64, 0f64);
            for (k, e) in epochs.iter().enumerate() {
                let command = CommandRef::PfRanges {
                    time_s: k as f64,
                    apriori_m: None,
                    sats: e,
                };
                fw.send(command)?;
                let r = fw.recv(raim_qemu::ANSWER_TIMEOUT)?;
                anyhow::ensure!(matches!(r.body, ResponseBody::PfResult(_)), "{r:?}");
                let ticks = fw.status()?.last_epoch_ticks as u64;
                let t = Instant::now();
                host_send(&mut host, host_seq, command);
                let dt = t.elapsed().as_secs_f64();
                host_seq += 1;
                if k >= 1 {
                    instr += ticks * INSTRUCTIONS_PER_TICK;
                    host_s += dt;
                }
            }
            let per = instr / (EPOCHS as u64 - 1);
            let mcycles = per as f64 * 1.5 / 1e6;
            println!(
                "| {kind:?} | {particles} | {n} | {per} | {mcycles:.1} | {} | {:.0} |",
                if mcycles < 168.0 { "yes" } else { "no" },
                host_s / (EPOCHS - 1) as f64 * 1e6
            );
        }
    }
    use raim_core::pf::{Ekf, GaPf, PfRaim, SirPf};
    const S: usize = raim_proto::pf_msg::PF_SATS;
    println!(
        "RAM (bytes): engines at {S} satellites, f32: EKF {}, GA-PF 100 {}, GA-PF 300 {} (SIR 300 {}, f64 GA-PF 300 {})",
        PfRaim::<f32, Ekf<f32>, S>::BYTES,
        PfRaim::<f32, GaPf<f32, 100>, S>::BYTES,
        PfRaim::<f32, GaPf<f32, 300>, S>::BYTES,
        PfRaim::<f32, SirPf<f32, 300>, S>::BYTES,
        PfRaim::<f64, GaPf<f64, 300>, S>::BYTES,
    );
    Ok(())
}
