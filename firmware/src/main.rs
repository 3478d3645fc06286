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
    let server = server();
    #[cfg(feature = "pf")]
    server.attach_pf(pf_engines());
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

/// The server (receive buffer, engines, transmit buffers) in a static; no
/// heap anywhere. Its own frame, not inlined: building the value passes
/// through the stack (with ARAIM, ~0.7 MB at boot, before the stack is
/// painted), and inlined into `main` that frame would stay reserved for the
/// whole main loop (BENCHMARKS.md, "ARAIM on the device").
#[inline(never)]
fn server() -> &'static mut Server {
    match cortex_m::singleton!(: Server = Server::new()) {
        Some(s) => s,
        None => board::halt(),
    }
}

/// The particle-filter engines (issue 14), each in its own zero-filled
/// static (`.bss`: no flash image, never built on the stack), handed to
/// the server for good. Called once, from `main`.
///
/// All-zero bytes are a valid value of every engine: its fields are `f32`
/// and `f64` arrays, integers, `Option<f64>` (its tag is 0 or 1, both
/// valid), `Option<SatId>` (`System` has a variant with discriminant 0, so
/// zero is a valid `SatId` whatever the niche), `heapless::Vec` (length
/// 0) and the generator's `[u64; 4]`. The server restarts an engine
/// (`PfRaim::restart`: fresh history, reseeded generator) at every
/// `PfConfigure` before its first epoch, and the first epoch overwrites the
/// particles, so the zero contents are never used (host-tests/tests/
/// qemu_pf.rs `a_zeroed_engine_restarted_equals_a_new_one`).
#[cfg(feature = "pf")]
fn pf_engines() -> raim_proto::server::PfEngines {
    use core::mem::MaybeUninit;
    use core::ptr::addr_of_mut;
    use raim_proto::server::{
        EkfEngine, Ga100Engine, Ga300Engine, Pf100Engine, Pf300Engine, PfEngines,
    };
    static mut EKF: MaybeUninit<EkfEngine> = MaybeUninit::zeroed();
    static mut PF100: MaybeUninit<Pf100Engine> = MaybeUninit::zeroed();
    static mut PF300: MaybeUninit<Pf300Engine> = MaybeUninit::zeroed();
    static mut GA100: MaybeUninit<Ga100Engine> = MaybeUninit::zeroed();
    static mut GA300: MaybeUninit<Ga300Engine> = MaybeUninit::zeroed();
    // SAFETY: zero is a valid value of each engine (above); this function
    // runs once (from `main`, which never returns), so each `&'static mut`
    // is the only reference to its static ever made; no interrupt handler
    // touches them.
    unsafe {
        PfEngines {
            ekf: Some((*addr_of_mut!(EKF)).assume_init_mut()),
            pf100: Some((*addr_of_mut!(PF100)).assume_init_mut()),
            pf300: Some((*addr_of_mut!(PF300)).assume_init_mut()),
            ga100: Some((*addr_of_mut!(GA100)).assume_init_mut()),
            ga300: Some((*addr_of_mut!(GA300)).assume_init_mut()),
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
