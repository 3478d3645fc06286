//! RAIM firmware for a Cortex-M4F: receives pseudorange epochs as framed
//! requests on the link UART, runs the integrity monitor on each
//! (`raim_core::Raim`), answers every frame with the result or a typed
//! error, and writes NMEA 0183 for every solved epoch on the second UART.
//! The protocol loop is `raim_server::Server`; this crate adds the
//! board (UARTs, ticks), the receive ring (`link_rx`, by interrupt), the
//! integrity-alarm output (`discrete`), logging and the fatal-error path.
//! Wire protocol: docs/PROTOCOL.md.
#![no_std]
#![no_main]

mod board;
mod discrete;
mod fault;
mod guard;
mod key;
mod link_rx;
mod provision;
mod stack;
mod statics;
mod unit_id;

use cortex_m::interrupt::InterruptNumber;
use cortex_m::peripheral::NVIC;
use cortex_m_rt::{entry, exception, ExceptionFrame};
use raim_core::Decision;
use raim_proto::{ResetCause, Status, TestFault};
use raim_server::{Platform, Server};

use board::{Board, Parts, Watchdog};
use statics::ConstStaticCell;

#[cfg(feature = "board-stm32f4")]
use defmt_rtt as _;
#[cfg(feature = "board-qemu")]
use defmt_semihosting as _;

/// What the server asks of the board (`raim_server::Platform`), from the
/// board's parts.
struct Unit<B: Board> {
    ticks: board::Ticks,
    /// Resets since power-on and the last cause (`fault::boot`).
    reset: (u32, ResetCause),
    /// The integrity-alarm discrete output.
    discrete: discrete::Discrete<B::Alarm>,
    /// The core clock running, Hz, and whether it is the board's fallback.
    clock: (u32, bool),
    /// The DWT cycle counter, when it counts (not under QEMU).
    cycles: Option<board::CycleCounter>,
}

/// An interrupt line by number, for the NVIC (no device crate).
#[derive(Clone, Copy)]
struct Irq(u16);

// SAFETY: the numbers used are interrupt lines of the board
// (`Board::LINK_RX_IRQ`, or the one `DefaultHandler` was entered for).
unsafe impl InterruptNumber for Irq {
    fn number(self) -> u16 {
        self.0
    }
}

impl<B: Board> Platform for Unit<B> {
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
    fn cycles(&mut self) -> Option<u32> {
        self.cycles.as_ref().map(board::CycleCounter::now)
    }
    fn on_epoch(&mut self, decision: Option<Decision>) {
        let now = self.ticks.now64();
        self.discrete.on_epoch(now, decision);
    }
    fn board_status(&mut self, status: &mut Status) {
        (status.uart_overruns, status.rx_ring_overflows) = link_rx::counters();
        status.alarm_output = self.discrete.update(self.ticks.now64());
        status.alarm_pin_asserted = self.discrete.pin_asserted();
        (status.core_clock_hz, status.clock_fallback) = self.clock;
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
    // SAFETY: first thing in `main`: nothing references `.ccmram` yet.
    #[cfg(feature = "board-stm32f4")]
    unsafe {
        statics::zero_ccm()
    };
    let Some(core) = cortex_m::Peripherals::take() else {
        board::halt()
    };
    let Some(parts) = board::Active::take() else {
        board::halt()
    };
    run::<board::Active>(core, parts)
}

/// The application on board `B`: the boot sequence, then the main loop.
/// Interrupts are masked on entry (`Board::take`).
fn run<B: Board<LinkRx = board::RxPort>>(mut core: cortex_m::Peripherals, parts: Parts<B>) -> ! {
    let Parts {
        mut link,
        link_rx,
        mut nmea,
        alarm,
        mut watchdog,
        core_hz,
        clock_fallback,
        reset,
        hardware_entropy,
    } = parts;
    let reset = fault::boot(reset);
    let server = server();
    #[cfg(feature = "pf")]
    server.attach_pf(pf_engines());
    // With a key provisioned in flash (`key`), only authenticated changes
    // are taken.
    let key = key::provisioned();
    if let Some(k) = key {
        server.set_auth_key(k);
    }
    let Some(mut rx) = link_rx::init(link_rx) else {
        board::halt()
    };
    let mut platform = Unit::<B> {
        ticks: board::Ticks::new(core.SYST),
        reset,
        discrete: discrete::Discrete::new(alarm, core_hz),
        clock: (core_hz, clock_fallback),
        cycles: board::CycleCounter::start(&mut core.DCB, &mut core.DWT),
    };
    // The boot counter in flash, raised before anything uses the nonce
    // it goes into (docs/SAFETY.md "Boot counter"). A counter that fails
    // leaves the boot without a count: a keyed unit then refuses every
    // authenticated change.
    let counter = match board::boot_flash::advance() {
        Ok(n) => {
            defmt::info!("boot counter: {=u32}", n);
            raim_proto::boot_counter::BootCounterStatus::Count(n)
        }
        // The error itself is in `Status` (its `defmt::Format` would cost
        // the small-flash build a few hundred bytes).
        Err(e) => {
            defmt::error!("boot counter failed");
            raim_proto::boot_counter::BootCounterStatus::Failed(e)
        }
    };
    server.set_boot_counter(counter);
    // The provisioned configuration, if its seal verifies and every part
    // passes its checks, runs locked; otherwise the unit is Unconfigured.
    // No default is ever put in force.
    let entropy = provision::entropy(
        platform.ticks.now(),
        hardware_entropy.as_ref(),
        B::unique_id(),
    );
    boot(server, key.as_ref(), reset.0, &entropy);
    watchdog.start();
    stack::paint();
    guard::enable(&mut core.MPU);
    defmt::info!(
        "raim firmware up: capacity {=usize}, protocol {=u16}, core {=u32} Hz, watchdog {=u32} ms",
        raim_proto::CAPACITY,
        raim_proto::PROTOCOL_VERSION,
        core_hz,
        watchdog.timeout_ms()
    );
    // The boot notice: the first frame after every reset.
    let _ = server.send_boot_notice::<_, core::convert::Infallible, _>(&mut link, &mut platform);
    // SAFETY: the ring and its interrupt side are set up (`link_rx::init`);
    // the handlers (`DefaultHandler`, `SysTick`) share only atomics and the
    // critical-section-guarded receive side with this loop.
    unsafe {
        NVIC::unmask(Irq(B::LINK_RX_IRQ));
        cortex_m::interrupt::enable();
    }
    // A pause on the link (`raim_server::LINK_IDLE_S`, or the test-only
    // build setting: `link_idle::LINK_IDLE_S`): ticks, and the time of the
    // last byte while no pause has been signalled since.
    let idle_ticks = (link_idle::LINK_IDLE_S * f64::from(core_hz)) as u64;
    let mut last_byte: Option<u64> = None;
    loop {
        while let Some(b) = rx.next() {
            // A UART error is the board's to count (`link_rx`); the
            // server's state is the same whether or not the answer went out.
            let _ = server.on_byte(b, &mut link, &mut nmea, &mut platform);
            watchdog.feed();
            last_byte = Some(platform.ticks.now64());
        }
        let now = platform.ticks.now64();
        if last_byte.is_some_and(|t| now.wrapping_sub(t) >= idle_ticks) {
            last_byte = None;
            let _ = server.on_line_idle(&mut link, &mut nmea, &mut platform);
            watchdog.feed();
        }
        platform.discrete.update(now);
        // Sleep until the next byte or SysTick wrap, unless a byte came in
        // since the ring was found empty: interrupts are masked between
        // the check and WFI (a pending interrupt still ends WFI, and its
        // handler runs once they are unmasked).
        cortex_m::interrupt::free(|cs| {
            if !rx.pump(cs) {
                watchdog.feed();
                cortex_m::asm::wfi();
            }
        });
    }
}

/// The link pause setting (build.rs `link_idle`).
mod link_idle {
    include!(concat!(env!("OUT_DIR"), "/link_idle.rs"));
}

/// The boot sequence's configuration step, in a frame of its own so that
/// the decoded unit configuration (with an ISM, ~1.5 KB) is not reserved on
/// `main`'s frame for the whole main loop.
#[inline(never)]
fn boot(
    server: &mut Server,
    key: Option<&raim_proto::AuthKey>,
    resets: u32,
    entropy: &raim_proto::auth::BootEntropy,
) {
    let provisioned = raim_proto::unit::open(provision::section(), key);
    server.boot(provisioned, resets, entropy);
}

/// SysTick's wrap (every 2^24 core ticks): extends the tick counter,
/// asserts the alarm output when no valid epoch came within the
/// time-to-alert (`discrete::on_wrap`, whatever the main loop is doing)
/// and wakes the waiting loop.
#[exception]
fn SysTick() {
    discrete::on_wrap(board::on_systick());
}

/// Every device interrupt (cortex-m-rt's `DefaultHandler` receives its
/// number; no device crate, no hand-written vector table): the link UART's
/// receive interrupt goes to `link_rx`. Any other line was never enabled;
/// should one fire, it is masked again.
#[exception]
unsafe fn DefaultHandler(irqn: i16) {
    if irqn == <board::Active as Board>::LINK_RX_IRQ as i16 {
        link_rx::on_irq();
    } else if let Ok(line) = u16::try_from(irqn) {
        NVIC::mask(Irq(line));
    } else {
        // A system exception without a handler (none is enabled).
        fault::record_and_reset(fault::CODE_HARD_FAULT, 0)
    }
}

/// The server (receive buffer, engines, transmit buffers) in a static
/// (`statics.rs`): its `const fn` constructor's value is in the image, so
/// it is never built on the stack (a run-time `Server::new()` passes
/// through a stack temporary: 94 KB on the STM32F4 build, more than its
/// stack). Called once, from `run`.
fn server() -> &'static mut Server {
    static SERVER: ConstStaticCell<Server> = ConstStaticCell::new(Server::new());
    statics::take(&SERVER)
}

/// The particle-filter engines of the QEMU board, each in its own static
/// (`statics.rs`) initialised with the engine's all-zero `EMPTY` value
/// (`.bss`), handed to the server for good. The server restarts an engine
/// (`PfRaim::restart`: fresh history, reseeded generator) at every
/// `PfConfigure` before its first epoch. Called once, from `run`.
#[cfg(all(feature = "pf", feature = "board-qemu"))]
fn pf_engines() -> raim_server::PfEngines {
    use raim_server::{EkfEngine, Ga100Engine, Ga300Engine, Pf100Engine, Pf300Engine, PfEngines};
    static EKF: ConstStaticCell<EkfEngine> = ConstStaticCell::new(EkfEngine::EMPTY);
    static PF100: ConstStaticCell<Pf100Engine> = ConstStaticCell::new(Pf100Engine::EMPTY);
    static PF300: ConstStaticCell<Pf300Engine> = ConstStaticCell::new(Pf300Engine::EMPTY);
    static GA100: ConstStaticCell<Ga100Engine> = ConstStaticCell::new(Ga100Engine::EMPTY);
    static GA300: ConstStaticCell<Ga300Engine> = ConstStaticCell::new(Ga300Engine::EMPTY);
    PfEngines {
        ekf: Some(statics::take(&EKF)),
        pf100: Some(statics::take(&PF100)),
        pf300: Some(statics::take(&PF300)),
        ga100: Some(statics::take(&GA100)),
        ga300: Some(statics::take(&GA300)),
    }
}

/// The STM32F4's particle-filter engine: the GA-PF at 100 particles
/// (59 KB), in the core-coupled memory (`.ccmram`, memory-stm32f4.x; only
/// the core reaches it and nothing here uses DMA), in the same pattern as
/// every other static: `main` zero-fills the section first
/// (`statics::zero_ccm`), and the engine's `EMPTY` value is all zero. The
/// other engines are left out: their `PfConfigure` is answered
/// `PfUnavailable`.
#[cfg(all(feature = "pf", feature = "board-stm32f4"))]
fn pf_engines() -> raim_server::PfEngines {
    use raim_server::{Ga100Engine, PfEngines};
    #[link_section = ".ccmram.raim_ga100"]
    static GA100: ConstStaticCell<Ga100Engine> = ConstStaticCell::new(Ga100Engine::EMPTY);
    PfEngines {
        ga100: Some(statics::take(&GA100)),
        ..PfEngines::NONE
    }
}

/// Fail loud: log, record the cause, reset.
///
/// The log carries the location and the message when it is a literal;
/// a message with run-time arguments (core's bounds checks, say) is not
/// formatted, so that `core::fmt` stays out of the flash (it
/// was ~1.7 KB for this one call); the location finds it in the source.
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    let (file, line, column) = info
        .location()
        .map_or(("?", 0, 0), |l| (l.file(), l.line(), l.column()));
    let message = info.message().as_str().unwrap_or("(formatted message)");
    defmt::error!(
        "panic at {=str}:{=u32}:{=u32}: {=str}",
        file,
        line,
        column,
        message
    );
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
