//! The board interface the application is generic over ([`Board`]), and
//! what every Cortex-M4 board shares (SysTick as the tick counter, the
//! fatal stop). One implementation per board feature:
//!
//! - `board-qemu` (default, CI): QEMU's `mps2-an386`, a Cortex-M4 with CMSDK
//!   APB UARTs and watchdog, on a small register layer (`mps2.rs`).
//! - `board-stm32f4`: an STM32F405/407 on `stm32f4xx-hal` (`stm32f4.rs`).
//!
//! A board hands over, once ([`Board::take`]): the link UART's transmit
//! side and the NMEA UART (`embedded_io::Write`), the link's receive side
//! for its interrupt ([`LinkRxPort`], driven by `link_rx`), the
//! integrity-alarm output (embedded-hal `OutputPin`), the watchdog
//! ([`Watchdog`]), the core clock in Hz, what the hardware says reset
//! the part ([`HardwareReset`]) and its hardware entropy, if any. The MPU and SysTick are the core's
//! (`cortex_m::Peripherals`), the same on every board.

use core::sync::atomic::{AtomicU32, Ordering};

use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::{DCB, DWT, SCB, SYST};
use embedded_hal::digital::{OutputPin, StatefulOutputPin};

pub mod boot_flash;
#[cfg(feature = "board-qemu")]
pub mod mps2;
#[cfg(feature = "board-stm32f4")]
mod rng_draw;
#[cfg(feature = "board-stm32f4")]
pub mod stm32f4;

/// The board this build runs on.
#[cfg(feature = "board-qemu")]
pub type Active = mps2::Mps2An386;
/// The board this build runs on.
#[cfg(feature = "board-stm32f4")]
pub type Active = stm32f4::Stm32f4;

/// The active board's link receive port (the interrupt side of `link_rx`
/// holds it in a static, so it names the concrete type).
pub type RxPort = <Active as Board>::LinkRx;

/// The receive side of the link UART, driven by its receive interrupt.
pub trait LinkRxPort {
    /// A byte is waiting in the UART.
    fn rx_ready(&self) -> bool;
    /// The waiting byte (call when `rx_ready`), if it could be read, and
    /// whether one was lost before it (overrun, framing, parity or noise;
    /// the flag is cleared here).
    fn read(&mut self) -> (Option<u8>, bool);
    /// Acknowledges the receive interrupt.
    fn ack(&mut self);
    /// Enables or disables the receive interrupt (reception itself stays
    /// on; a byte then waits in the UART).
    fn set_irq(&mut self, on: bool);
}

/// The watchdog: started once, after the boot sequence, then fed by the
/// main loop while it waits for bytes and after every byte it handles. An
/// epoch that hangs stops the feeding; the watchdog then resets the unit
/// (docs/SAFETY.md "Watchdog").
pub trait Watchdog {
    /// The nominal timeout, ms: the board's choice for the clock it runs
    /// at, so that the costliest epoch takes under half the shortest
    /// timeout (docs/SAFETY.md "Watchdog margin").
    fn timeout_ms(&self) -> u32;
    /// Starts it with [`Self::timeout_ms`]; it cannot be stopped again.
    fn start(&mut self);
    /// Restarts its countdown.
    fn feed(&mut self);
}

/// What the hardware says reset the part (the fault record in RAM,
/// `fault`, says why when the firmware recorded the cause itself).
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum HardwareReset {
    /// A power-on or brown-out reset: RAM holds no record.
    PowerOn,
    /// The independent watchdog expired (no handler ran: the STM32F4's
    /// IWDG resets without an early interrupt).
    Watchdog,
    /// Anything else (pin, software), or a board with no reset-cause
    /// register (QEMU's mps2-an386; QEMU's netduinoplus2 reads 0).
    Other,
}

/// Everything a board hands to the application, once.
pub struct Parts<B: Board> {
    /// The link UART's transmit side (answers, boot notice).
    pub link: B::Link,
    /// The link UART's receive side, for its interrupt.
    pub link_rx: B::LinkRx,
    /// The NMEA UART (transmit only).
    pub nmea: B::Nmea,
    /// The integrity-alarm discrete output, at its alarm (low) level.
    pub alarm: B::Alarm,
    /// The watchdog, not yet started.
    pub watchdog: B::Watchdog,
    /// The core clock actually running, Hz (SysTick counts at it).
    pub core_hz: u32,
    /// True when the board runs on a fallback clock because its intended
    /// one did not start (the STM32F4 on its HSI when the HSE or the PLL
    /// timed out); reported in `Status`.
    pub clock_fallback: bool,
    /// What reset the part.
    pub reset: HardwareReset,
    /// 32 bytes from the board's hardware random source, read without
    /// error at start-up, for the boot nonce; `None` when the board has
    /// none (mps2-an386) or it failed or timed out (the STM32F4's RNG;
    /// always under QEMU's netduinoplus2, which does not model it).
    pub hardware_entropy: Option<[u8; 32]>,
}

/// A board: its peripherals' types and how to take them.
pub trait Board: Sized {
    /// The link UART's transmit side.
    type Link: embedded_io::Write;
    /// The NMEA UART.
    type Nmea: embedded_io::Write;
    /// The link UART's receive side.
    type LinkRx: LinkRxPort + Send;
    /// The integrity-alarm output, active low.
    type Alarm: OutputPin + StatefulOutputPin;
    /// The watchdog.
    type Watchdog: Watchdog;
    /// The link's receive interrupt line (NVIC number).
    const LINK_RX_IRQ: u16;
    /// Drives the integrity-alarm output to its alarm (low) level from an
    /// interrupt handler, without the pin's owner: one register write that
    /// cannot leave the pin at the clear level (the time-to-alert timer,
    /// `discrete::on_wrap`). Only ever asserts.
    fn force_alarm();
    /// The part's factory-programmed unique ID, where the board has one
    /// (the STM32F4's 96 bits), for the boot nonce (`unit_id`).
    fn unique_id() -> Option<[u32; 3]>;
    /// The board's peripherals, set up (clocks, pins, UARTs at 115200 8N1),
    /// with interrupts masked (PRIMASK) until the application has set up
    /// the receive ring. `None` if called twice, or if the
    /// board cannot start (the STM32F4: its clock unknown); `main` then halts.
    fn take() -> Option<Parts<Self>>;
}

/// Wraps of SysTick's 24-bit counter since boot (its exception, `main.rs`).
static WRAPS: AtomicU32 = AtomicU32::new(0);

/// The SysTick exception's work: one more wrap; returns the wraps since
/// boot, this one included.
pub fn on_systick() -> u32 {
    WRAPS.fetch_add(1, Ordering::Relaxed).wrapping_add(1)
}

/// SysTick as a free-running 24-bit counter at the core clock, extended to
/// 64 bits by counting its wraps in its exception (every 2^24 ticks:
/// 0.67 s at 25 MHz, 0.10 s at 168 MHz, 1.05 s at 16 MHz). The exception
/// also wakes the waiting loop, which feeds the watchdog and checks the
/// time-to-alert.
pub struct Ticks(SYST);

impl Ticks {
    pub fn new(mut syst: SYST) -> Self {
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(0x00FF_FFFF);
        syst.clear_current();
        syst.enable_counter();
        syst.enable_interrupt();
        Ticks(syst)
    }
    /// Counts up (SysTick counts down).
    pub fn now(&self) -> u32 {
        0x00FF_FFFF - SYST::get_current()
    }
    /// Ticks since boot, 64 bits. A wrap whose exception has not run yet
    /// (interrupts masked) is seen through SysTick's pending bit.
    pub fn now64(&self) -> u64 {
        cortex_m::interrupt::free(|_| {
            let mut wraps = WRAPS.load(Ordering::Relaxed);
            let mut count = self.now();
            if SCB::is_pendst_pending() {
                wraps = wraps.wrapping_add(1);
                count = self.now();
            }
            (u64::from(wraps) << 24) | u64::from(count)
        })
    }
}

/// The core's cycle counter (the DWT's CYCCNT, ARMv7-M ARM C1.8.6), for
/// `Status.epoch_cycles`: a real board reports its own epochs' cycles.
/// Started once at boot, and only kept when it is seen to count: QEMU does
/// not model the DWT (its registers read 0 and ignore writes, so CYCCNT
/// stays 0), and the unit then reports "not measured", never a zero
/// count.
pub struct CycleCounter(());

impl CycleCounter {
    /// Enables tracing (DEMCR.TRCENA) and the counter, then checks that
    /// it advances over a short busy wait; `None` when the core has no
    /// counter or it does not count.
    pub fn start(dcb: &mut DCB, dwt: &mut DWT) -> Option<Self> {
        if !DWT::has_cycle_counter() {
            return None;
        }
        dcb.enable_trace();
        dwt.enable_cycle_counter();
        let c0 = DWT::cycle_count();
        cortex_m::asm::delay(64);
        (DWT::cycle_count() != c0).then_some(CycleCounter(()))
    }

    /// Core clock cycles, wrapping at 2^32.
    pub fn now(&self) -> u32 {
        DWT::cycle_count()
    }
}

/// Stop for good after a fatal error has been reported: under QEMU, end
/// the emulator with a failure status (the host sees the link close); on a
/// board, sleep with interrupts off until a debugger or reset intervenes.
pub fn halt() -> ! {
    cortex_m::interrupt::disable();
    #[cfg(feature = "board-qemu")]
    cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::wfi();
    }
}

#[cfg(all(feature = "board-qemu", feature = "board-stm32f4"))]
compile_error!("choose one board feature");
#[cfg(not(any(feature = "board-qemu", feature = "board-stm32f4")))]
compile_error!("choose a board feature: board-qemu or board-stm32f4");
