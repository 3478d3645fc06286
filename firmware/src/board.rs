//! Everything board-specific, in one module: the two UARTs (transmit
//! behind `embedded_io::Write`; the link's receive side for its interrupt,
//! `link_rx`), the tick counter, the integrity-alarm output (behind
//! embedded-hal's `OutputPin`), and how to stop after a fatal error.
//!
//! - `board-qemu` (default, CI): QEMU's `mps2-an386`, a Cortex-M4 with CMSDK
//!   APB UARTs: UART0 (0x4000_4000) is the frame link, UART1 (0x4000_5000)
//!   the NMEA output.
//! - `board-stm32f4`: an STM32F407-class part at its 16 MHz reset clock:
//!   USART2 (PA2/PA3) is the link, USART3 (PB10/PB11) the NMEA output, both
//!   115200 8N1.

#[cfg(feature = "board-qemu")]
use core::convert::Infallible;
#[cfg(feature = "board-qemu")]
use core::ptr::{read_volatile, write_volatile};

use core::sync::atomic::{AtomicU32, Ordering};

use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::{SCB, SYST};

/// A memory-mapped register block at a fixed address (the QEMU board,
/// which has no HAL).
#[cfg(feature = "board-qemu")]
#[derive(Clone, Copy)]
struct Regs(usize);

#[cfg(feature = "board-qemu")]
impl Regs {
    fn read(self, offset: usize) -> u32 {
        // SAFETY: the address is a device register of this board (see the
        // constructors), aligned and always mapped.
        unsafe { read_volatile((self.0 + offset) as *const u32) }
    }
    fn write(self, offset: usize, v: u32) {
        // SAFETY: as for `read`.
        unsafe { write_volatile((self.0 + offset) as *mut u32, v) }
    }
}

#[cfg(feature = "board-qemu")]
mod uart {
    use super::Regs;

    /// CMSDK APB UART (ARM DDI 0479C §4.3): the transmit side.
    pub struct Uart(Regs);
    /// The receive side of the link UART, driven by its RX interrupt
    /// (`link_rx`).
    pub struct RxPort(Regs);

    const DATA: usize = 0x00;
    const STATE: usize = 0x04;
    const CTRL: usize = 0x08;
    const INTSTATUS: usize = 0x0C;
    const BAUDDIV: usize = 0x10;
    const STATE_TX_FULL: u32 = 1 << 0;
    const STATE_RX_FULL: u32 = 1 << 1;
    const STATE_RX_OVERRUN: u32 = 1 << 3;
    const CTRL_TX_EN: u32 = 1 << 0;
    const CTRL_RX_EN: u32 = 1 << 1;
    const CTRL_RX_INTEN: u32 = 1 << 3;
    const INTSTATUS_RX: u32 = 1 << 1;
    /// 25 MHz / 115200 baud.
    const BAUDDIV_115200: u32 = 217;

    pub const UART0: usize = 0x4000_4000;
    pub const UART1: usize = 0x4000_5000;
    /// UART0's RX interrupt line on mps2-an385/an386 (QEMU `hw/arm/mps2.c`:
    /// RX lines 0, 2, 4, 18, 20 for UART0-4; TX one above each).
    pub const LINK_RX_IRQ: u16 = 0;

    impl Uart {
        /// # Safety
        /// `base` is a CMSDK UART of this machine, owned by nobody else.
        /// With `rx`, reception and its interrupt are enabled too.
        pub unsafe fn new(base: usize, rx: bool) -> Self {
            let r = Regs(base);
            r.write(BAUDDIV, BAUDDIV_115200);
            let rx_bits = if rx { CTRL_RX_EN | CTRL_RX_INTEN } else { 0 };
            r.write(CTRL, CTRL_TX_EN | rx_bits);
            Uart(r)
        }
        /// The receive side of a UART made with `rx`.
        pub fn rx_port(&self) -> RxPort {
            RxPort(self.0)
        }
        pub fn tx_ready(&self) -> bool {
            self.0.read(STATE) & STATE_TX_FULL == 0
        }
        pub fn write_byte(&mut self, b: u8) {
            while !self.tx_ready() {}
            self.0.write(DATA, u32::from(b));
        }
    }

    impl RxPort {
        pub fn rx_ready(&self) -> bool {
            self.0.read(STATE) & STATE_RX_FULL != 0
        }
        /// The waiting byte (call when `rx_ready`) and whether the UART
        /// overran before it (cleared here).
        pub fn read(&mut self) -> (Option<u8>, bool) {
            let overrun = self.0.read(STATE) & STATE_RX_OVERRUN != 0;
            if overrun {
                self.0.write(STATE, STATE_RX_OVERRUN);
            }
            (Some(self.0.read(DATA) as u8), overrun)
        }
        /// Acknowledge the RX interrupt (write-one-to-clear).
        pub fn ack(&mut self) {
            self.0.write(INTSTATUS, INTSTATUS_RX);
        }
        /// Enable or disable the RX interrupt (reception itself stays on;
        /// the byte waits in the UART).
        pub fn set_irq(&mut self, on: bool) {
            let c = self.0.read(CTRL);
            self.0.write(
                CTRL,
                if on {
                    c | CTRL_RX_INTEN
                } else {
                    c & !CTRL_RX_INTEN
                },
            );
        }
    }
}

/// The STM32F4 board on `stm32f4xx-hal` (embedded-hal 1.0): the HAL sets
/// up the pins, the USARTs and the alarm pin; this module only adapts its
/// non-blocking transmitter to `embedded_io::Write` and its receiver to
/// the receive port `link_rx` drives.
#[cfg(feature = "board-stm32f4")]
mod uart {
    use stm32f4xx_hal::gpio::{Output, PushPull, PD12};
    use stm32f4xx_hal::pac;
    use stm32f4xx_hal::prelude::*;
    use stm32f4xx_hal::serial::{self, RxISR, RxListen, Serial};

    /// A USART's transmit side (blocking `embedded_io::Write`).
    pub struct Uart<U: serial::Instance>(serial::Tx<U, u8>);
    /// The link USART's receive side, driven by its RXNE interrupt.
    pub struct RxPort(serial::Rx<pac::USART2, u8>);
    /// PD12 (the green LED of an STM32F4-Discovery), push-pull; the HAL's
    /// pin implements embedded-hal's `OutputPin` and `StatefulOutputPin`.
    pub type AlarmPin = PD12<Output<PushPull>>;

    /// USART2's interrupt (RM0090 Table 61, position 38).
    pub const LINK_RX_IRQ: u16 = pac::Interrupt::USART2 as u16;

    /// The link (USART2 on PA2/PA3), the NMEA output (USART3 TX on PB10)
    /// and the alarm pin (PD12, at its alarm level), all 115200 8N1. The
    /// clocks stay at the 16 MHz HSI the part resets to: `constrain`
    /// configures nothing, so nothing waits for a ready bit (QEMU's
    /// netduinoplus2 does not model the RCC; docs/SAFETY.md).
    pub fn parts() -> Option<(Uart<pac::USART2>, RxPort, Uart<pac::USART3>, AlarmPin)> {
        let dp = pac::Peripherals::take()?;
        let mut rcc = dp.RCC.constrain();
        let gpioa = dp.GPIOA.split(&mut rcc);
        let gpiob = dp.GPIOB.split(&mut rcc);
        let gpiod = dp.GPIOD.split(&mut rcc);
        let config = serial::Config::default().baudrate(115_200.bps());
        let link = Serial::new(dp.USART2, (gpioa.pa2, gpioa.pa3), config, &mut rcc).ok()?;
        let (link_tx, mut link_rx) = link.split();
        link_rx.listen();
        let nmea = dp.USART3.tx(gpiob.pb10, config, &mut rcc).ok()?;
        let alarm = gpiod.pd12.into_push_pull_output_in_state(false.into());
        Some((Uart(link_tx), RxPort(link_rx), Uart(nmea), alarm))
    }

    impl<U: serial::Instance> embedded_io::ErrorType for Uart<U> {
        type Error = serial::Error;
    }

    impl<U: serial::Instance> embedded_io::Write for Uart<U>
    where
        serial::Tx<U, u8>: embedded_hal_nb::serial::Write<u8, Error = serial::Error>,
    {
        /// Blocks until every byte is in the transmitter (the HAL's own
        /// `write` returns `Ok(0)` when busy, which `write_all` forbids).
        fn write(&mut self, buf: &[u8]) -> Result<usize, serial::Error> {
            for &b in buf {
                nb::block!(embedded_hal_nb::serial::Write::write(&mut self.0, b))?;
            }
            Ok(buf.len())
        }
        fn flush(&mut self) -> Result<(), serial::Error> {
            nb::block!(embedded_hal_nb::serial::Write::flush(&mut self.0))
        }
    }

    impl RxPort {
        pub fn rx_ready(&self) -> bool {
            self.0.is_rx_not_empty()
        }
        /// The waiting byte, if it could be read, and whether one was
        /// lost: an overrun, or a framing, parity or noise error (the HAL
        /// reads the data register to clear them and drops the byte).
        pub fn read(&mut self) -> (Option<u8>, bool) {
            match embedded_hal_nb::serial::Read::read(&mut self.0) {
                Ok(b) => (Some(b), false),
                Err(nb::Error::WouldBlock) => (None, false),
                Err(nb::Error::Other(_)) => (None, true),
            }
        }
        /// RXNE clears when the data register is read.
        pub fn ack(&mut self) {}
        pub fn set_irq(&mut self, on: bool) {
            if on {
                self.0.listen()
            } else {
                self.0.unlisten()
            }
        }
    }
}

#[cfg(feature = "board-stm32f4")]
pub use uart::AlarmPin;
pub use uart::{RxPort, Uart, LINK_RX_IRQ};

#[cfg(feature = "board-qemu")]
impl embedded_io::ErrorType for Uart {
    type Error = Infallible;
}

#[cfg(feature = "board-qemu")]
impl embedded_io::Write for Uart {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Infallible> {
        for &b in buf {
            self.write_byte(b);
        }
        Ok(buf.len())
    }
    fn flush(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
}

/// The link UART (transmit side, and its receive port for `link_rx`), the
/// NMEA UART (transmit only) and the integrity-alarm pin (at its alarm
/// level). Interrupts stay masked (PRIMASK) until `main` has set up the
/// receive ring. `None` if called twice.
#[cfg(feature = "board-qemu")]
pub fn parts() -> Option<(Uart, RxPort, Uart, AlarmPin)> {
    use core::sync::atomic::AtomicBool;
    static TAKEN: AtomicBool = AtomicBool::new(false);
    cortex_m::interrupt::disable();
    if TAKEN.swap(true, Ordering::Relaxed) {
        return None;
    }
    // SAFETY: taken once (above); UART0/UART1 are used nowhere else.
    let (link, nmea) = unsafe { (Uart::new(uart::UART0, true), Uart::new(uart::UART1, false)) };
    let rx = link.rx_port();
    Some((link, rx, nmea, AlarmPin::new()))
}

#[cfg(feature = "board-stm32f4")]
pub fn parts() -> Option<(
    Uart<stm32f4xx_hal::pac::USART2>,
    RxPort,
    Uart<stm32f4xx_hal::pac::USART3>,
    AlarmPin,
)> {
    cortex_m::interrupt::disable();
    uart::parts()
}

/// The core clock, Hz: SysTick counts at it.
#[cfg(feature = "board-qemu")]
pub const CORE_HZ: u32 = 25_000_000;
/// The 16 MHz HSI the STM32F4 resets to (no PLL: docs/SAFETY.md).
#[cfg(feature = "board-stm32f4")]
pub const CORE_HZ: u32 = 16_000_000;

/// Wraps of SysTick's 24-bit counter since boot (its exception, `main.rs`).
static WRAPS: AtomicU32 = AtomicU32::new(0);

/// The SysTick exception's work: one more wrap.
pub fn on_systick() {
    WRAPS.fetch_add(1, Ordering::Relaxed);
}

/// SysTick as a free-running 24-bit counter at the core clock, extended to
/// 64 bits by counting its wraps in its exception (every 2^24 ticks:
/// 0.67 s at 25 MHz, 1.05 s at 16 MHz). The exception also wakes the
/// waiting loop, which feeds the watchdog and checks the time-to-alert.
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

/// The integrity-alarm discrete output of the QEMU board,
/// behind embedded-hal 1.0's `OutputPin` and `StatefulOutputPin` (the
/// STM32F4's is the HAL's PD12). Active low on both boards: the pin is
/// driven high only while integrity is assured, so a unit that stops,
/// resets or loses power shows the alarm (docs/SAFETY.md).
/// `StatefulOutputPin` reads the level back from the register.
///
/// The FPGA I/O block of mps2-an385/an386 (0x4002_8000, register LED0 at
/// offset 0, bit 0: the first user LED; QEMU `hw/misc/mps2-fpgaio.c`).
#[cfg(feature = "board-qemu")]
pub struct AlarmPin(Regs);

#[cfg(feature = "board-qemu")]
mod pin {
    pub const FPGAIO: usize = 0x4002_8000;
    /// LED0: written and read back.
    pub const LED0: usize = 0x00;
    pub const BIT: u32 = 1 << 0;
}

#[cfg(feature = "board-qemu")]
impl AlarmPin {
    /// The pin, at its alarm level.
    fn new() -> Self {
        let mut p = AlarmPin(Regs(pin::FPGAIO));
        p.level(false);
        p
    }
    fn level(&mut self, high: bool) {
        let v = self.0.read(pin::LED0);
        self.0
            .write(pin::LED0, if high { v | pin::BIT } else { v & !pin::BIT });
    }
}

#[cfg(feature = "board-qemu")]
impl embedded_hal::digital::ErrorType for AlarmPin {
    type Error = Infallible;
}

#[cfg(feature = "board-qemu")]
impl embedded_hal::digital::OutputPin for AlarmPin {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.level(false);
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        self.level(true);
        Ok(())
    }
}

#[cfg(feature = "board-qemu")]
impl embedded_hal::digital::StatefulOutputPin for AlarmPin {
    fn is_set_high(&mut self) -> Result<bool, Infallible> {
        Ok(self.0.read(pin::LED0) & pin::BIT != 0)
    }
    fn is_set_low(&mut self) -> Result<bool, Infallible> {
        Ok(self.0.read(pin::LED0) & pin::BIT == 0)
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
