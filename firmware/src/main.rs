//! RAIM firmware for a Cortex-M4F: receives pseudorange epochs as framed
//! requests on the link UART, runs the integrity monitor on each
//! (`raim_core::Raim`), answers every frame with the result or a typed
//! error, and writes NMEA 0183 for every solved epoch on the second UART.
//! The protocol loop is `raim_proto::server::Server`; this crate adds the
//! board (UARTs, ticks), logging and the fatal-error path.
//! Wire protocol: docs/PROTOCOL.md.
#![no_std]
#![no_main]

mod board;
mod stack;

use cortex_m_rt::{entry, exception, ExceptionFrame};
use embedded_io::Read;
use raim_proto::server::{Platform, Server};

#[cfg(feature = "board-stm32f4")]
use defmt_rtt as _;
#[cfg(feature = "board-qemu")]
use defmt_semihosting as _;

struct Board {
    ticks: board::Ticks,
}

impl Platform for Board {
    const TICK_MASK: u32 = 0x00FF_FFFF;
    fn now(&mut self) -> u32 {
        self.ticks.now()
    }
    fn stack_high_water_bytes(&mut self) -> u32 {
        stack::high_water_bytes()
    }
}

#[entry]
fn main() -> ! {
    let Some(core) = cortex_m::Peripherals::take() else {
        board::halt()
    };
    // The server (receive buffer, engine, transmit buffers) lives in a
    // static; no heap anywhere.
    let Some(server) = cortex_m::singleton!(: Server = Server::new()) else {
        board::halt()
    };
    let (mut link, mut nmea) = board::uarts();
    let mut platform = Board {
        ticks: board::Ticks::new(core.SYST),
    };
    stack::paint();
    defmt::info!(
        "raim firmware up: capacity {=usize}, protocol {=u16}",
        raim_proto::CAPACITY,
        raim_proto::PROTOCOL_VERSION
    );
    let mut buf = [0u8; 64];
    loop {
        let Ok(n) = link.read(&mut buf);
        for &b in buf.iter().take(n) {
            // The UARTs' error type is Infallible.
            let _ = server.on_byte(b, &mut link, &mut nmea, &mut platform);
        }
    }
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    defmt::error!("panic: {}", defmt::Display2Format(info));
    board::halt()
}

#[exception]
unsafe fn HardFault(ef: &ExceptionFrame) -> ! {
    defmt::error!("hard fault at pc {=u32:#010x}", ef.pc());
    board::halt()
}
