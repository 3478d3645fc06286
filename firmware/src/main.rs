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
mod fault;
mod guard;
mod stack;
mod watchdog;

use cortex_m_rt::{entry, exception, ExceptionFrame};
use embedded_io::Read;
use raim_proto::server::{Platform, Server};
use raim_proto::{ResetCause, TestFault};

#[cfg(feature = "board-stm32f4")]
use defmt_rtt as _;
#[cfg(feature = "board-qemu")]
use defmt_semihosting as _;

struct Board {
    ticks: board::Ticks,
    /// Resets since power-on and the last cause (`fault::boot`).
    reset: (u32, ResetCause),
}

impl Platform for Board {
    const TICK_MASK: u32 = 0x00FF_FFFF;
    fn now(&mut self) -> u32 {
        self.ticks.now()
    }
    fn stack_high_water_bytes(&mut self) -> u32 {
        stack::high_water_bytes()
    }
    fn reset_record(&mut self) -> (u32, ResetCause) {
        self.reset
    }
    /// Test hooks exist on the QEMU board only (CI); the real board's
    /// build answers `TestHooksDisabled`.
    #[cfg(feature = "board-qemu")]
    fn test_fault(&mut self, fault: TestFault) -> bool {
        match fault {
            TestFault::Hang => loop {
                cortex_m::asm::nop();
            },
            // Deliberate: the fail-loud test (host-tests/tests/qemu_fail_loud.rs)
            // checks that a panic is recorded and the unit resets. Reachable only
            // from a `TestFault` frame, on the QEMU board build only.
            TestFault::Panic => panic!("test hook"),
            TestFault::StackOverflow => guard::overflow(0) != 0,
        }
    }
    #[cfg(not(feature = "board-qemu"))]
    fn test_fault(&mut self, _fault: TestFault) -> bool {
        false
    }
}

#[entry]
fn main() -> ! {
    let reset = fault::boot();
    let Some(core) = cortex_m::Peripherals::take() else {
        board::halt()
    };
    // The server (receive buffer, engine, transmit buffers) lives in a
    // static; no heap anywhere.
    let Some(server) = cortex_m::singleton!(: Server = Server::new()) else {
        board::halt()
    };
    #[cfg(feature = "pf")]
    {
        // The particle-filter state (~160 KiB) in its own static, zero-filled
        // by the startup code (`PfUnit::EMPTY` is a constant): never on the
        // stack. Lent to the server for good.
        static mut PF_UNIT: raim_proto::server::PfUnit = raim_proto::server::PfUnit::EMPTY;
        // SAFETY: `main` runs once and never returns, so this is the only
        // reference to PF_UNIT ever made; no interrupt handler touches it.
        let unit = unsafe { &mut *core::ptr::addr_of_mut!(PF_UNIT) };
        server.attach_pf(unit);
    }
    let (mut link, mut nmea) = board::uarts();
    let mut platform = Board {
        ticks: board::Ticks::new(core.SYST),
        reset,
    };
    watchdog::start();
    stack::paint();
    guard::enable();
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
            watchdog::feed();
        }
    }
}

/// Fail loud (issue 15): log, record the cause, reset.
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    defmt::error!("panic: {}", defmt::Display2Format(info));
    let line = info.location().map_or(0, |l| l.line());
    fault::record_and_reset(fault::CODE_PANIC, line)
}

#[exception]
unsafe fn HardFault(ef: &ExceptionFrame) -> ! {
    let frame = core::ptr::from_ref(ef) as usize;
    if guard::hit(frame) {
        // Stacked inside the guard: a stack overflow. Reset at once.
        fault::record_and_reset(fault::CODE_STACK_OVERFLOW, frame as u32)
    }
    defmt::error!("hard fault at pc {=u32:#010x}", ef.pc());
    fault::record_and_reset(fault::CODE_HARD_FAULT, ef.pc())
}

/// The watchdog's first expiry (mps2-an386: its interrupt is the NMI).
/// `unsafe` as cortex-m-rt requires of an NMI handler (it may preempt
/// anything); it shares nothing with the interrupted code but the record.
#[exception]
unsafe fn NonMaskableInt() {
    fault::record_and_reset(fault::CODE_WATCHDOG, 0)
}
