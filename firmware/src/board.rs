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

use core::convert::Infallible;
use core::ptr::{read_volatile, write_volatile};

use core::sync::atomic::{AtomicU32, Ordering};

use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::{SCB, SYST};

/// A memory-mapped register block at a fixed address.
#[derive(Clone, Copy)]
struct Regs(usize);

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
        pub fn read(&mut self) -> (u8, bool) {
            let overrun = self.0.read(STATE) & STATE_RX_OVERRUN != 0;
            if overrun {
                self.0.write(STATE, STATE_RX_OVERRUN);
            }
            (self.0.read(DATA) as u8, overrun)
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

#[cfg(feature = "board-stm32f4")]
mod uart {
    use super::Regs;

    /// STM32F4 USART (RM0090 §30.6): the transmit side.
    pub struct Uart(Regs);
    /// The receive side of the link USART, driven by its RXNE interrupt.
    pub struct RxPort(Regs);

    const SR: usize = 0x00;
    const DR: usize = 0x04;
    const BRR: usize = 0x08;
    const CR1: usize = 0x0C;
    const SR_RXNE: u32 = 1 << 5;
    const SR_TXE: u32 = 1 << 7;
    const SR_ORE: u32 = 1 << 3;
    const CR1_UE: u32 = 1 << 13;
    const CR1_RXNEIE: u32 = 1 << 5;
    const CR1_TE: u32 = 1 << 3;
    const CR1_RE: u32 = 1 << 2;
    /// 16 MHz HSI / 115200 = 138.9 -> mantissa 8, fraction 11 (0x8B).
    const BRR_115200_AT_16MHZ: u32 = 0x8B;

    pub const USART2: usize = 0x4000_4400;
    pub const USART3: usize = 0x4000_4800;
    /// USART2's interrupt (RM0090 Table 61, position 38).
    pub const LINK_RX_IRQ: u16 = 38;
    const RCC: usize = 0x4002_3800;
    const RCC_AHB1ENR: usize = 0x30;
    const RCC_APB1ENR: usize = 0x40;
    const GPIOA: usize = 0x4002_0000;
    const GPIOB: usize = 0x4002_0400;
    const MODER: usize = 0x00;
    const AFRL: usize = 0x20;
    const AFRH: usize = 0x24;

    /// Clocks and pins: GPIOA/B/D, USART2/3; PA2/PA3 and PB10/PB11 to AF7.
    /// The core stays on the 16 MHz HSI it resets to: nothing waits for a
    /// ready bit (docs/SAFETY.md).
    pub fn init_pins() {
        let rcc = Regs(RCC);
        rcc.write(RCC_AHB1ENR, rcc.read(RCC_AHB1ENR) | 0b1011);
        rcc.write(RCC_APB1ENR, rcc.read(RCC_APB1ENR) | (1 << 17) | (1 << 18));
        let (a, b) = (Regs(GPIOA), Regs(GPIOB));
        a.write(MODER, (a.read(MODER) & !(0xF << 4)) | (0b1010 << 4));
        a.write(AFRL, (a.read(AFRL) & !(0xFF << 8)) | (0x77 << 8));
        b.write(MODER, (b.read(MODER) & !(0xF << 20)) | (0b1010 << 20));
        b.write(AFRH, (b.read(AFRH) & !(0xFF << 8)) | (0x77 << 8));
    }

    impl Uart {
        /// # Safety
        /// `base` is a USART of this part, clocked, owned by nobody else.
        /// With `rx`, reception and its RXNE interrupt are enabled too.
        pub unsafe fn new(base: usize, rx: bool) -> Self {
            let r = Regs(base);
            r.write(BRR, BRR_115200_AT_16MHZ);
            let rx_bits = if rx { CR1_RE | CR1_RXNEIE } else { 0 };
            r.write(CR1, CR1_UE | CR1_TE | rx_bits);
            Uart(r)
        }
        pub fn rx_port(&self) -> RxPort {
            RxPort(self.0)
        }
        pub fn tx_ready(&self) -> bool {
            self.0.read(SR) & SR_TXE != 0
        }
        pub fn write_byte(&mut self, b: u8) {
            while !self.tx_ready() {}
            self.0.write(DR, u32::from(b));
        }
    }

    impl RxPort {
        pub fn rx_ready(&self) -> bool {
            self.0.read(SR) & (SR_RXNE | SR_ORE) != 0
        }
        /// The waiting byte and whether the USART overran before it.
        /// Reading SR then DR clears RXNE and ORE.
        pub fn read(&mut self) -> (u8, bool) {
            let overrun = self.0.read(SR) & SR_ORE != 0;
            (self.0.read(DR) as u8, overrun)
        }
        /// RXNE clears when DR is read: nothing to acknowledge.
        pub fn ack(&mut self) {}
        pub fn set_irq(&mut self, on: bool) {
            let c = self.0.read(CR1);
            self.0
                .write(CR1, if on { c | CR1_RXNEIE } else { c & !CR1_RXNEIE });
        }
    }
}

pub use uart::{RxPort, Uart, LINK_RX_IRQ};

impl embedded_io::ErrorType for Uart {
    type Error = Infallible;
}

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

/// The link UART (receive by interrupt, `link_rx`) and the NMEA UART
/// (transmit only). Interrupts stay masked (PRIMASK) until `main` has set
/// up the receive ring.
pub fn uarts() -> (Uart, Uart) {
    cortex_m::interrupt::disable();
    #[cfg(feature = "board-qemu")]
    // SAFETY: called once from `main`; UART0/UART1 are used nowhere else.
    unsafe {
        (Uart::new(uart::UART0, true), Uart::new(uart::UART1, false))
    }
    #[cfg(feature = "board-stm32f4")]
    // SAFETY: called once from `main`; USART2/USART3 are used nowhere else.
    unsafe {
        uart::init_pins();
        (
            Uart::new(uart::USART2, true),
            Uart::new(uart::USART3, false),
        )
    }
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

/// The integrity-alarm discrete output (issue 15) behind embedded-hal 1.0's
/// `OutputPin` and `StatefulOutputPin`. Active low: the pin is driven high
/// only while integrity is assured, so a unit that stops, resets or loses
/// power shows the alarm (docs/SAFETY.md). `StatefulOutputPin` reads the
/// level back from the hardware's output register.
///
/// - `board-qemu`: the FPGA I/O block of mps2-an385/an386 (0x4002_8000,
///   register LED0 at offset 0, bit 0: the first user LED; QEMU
///   `hw/misc/mps2-fpgaio.c`).
/// - `board-stm32f4`: PD12 (the green LED of an STM32F4-Discovery), push-pull.
pub struct AlarmPin(Regs);

#[cfg(feature = "board-qemu")]
mod pin {
    pub const BASE: usize = 0x4002_8000;
    /// LED0: written and read back.
    pub const OUT: usize = 0x00;
    pub const SET: Option<usize> = None;
    pub const BIT: u32 = 1 << 0;
}

#[cfg(feature = "board-stm32f4")]
mod pin {
    /// GPIOD (clocked in `uart::init_pins`).
    pub const BASE: usize = 0x4002_0C00;
    pub const MODER: usize = 0x00;
    /// ODR, read back.
    pub const OUT: usize = 0x14;
    /// BSRR: atomic set (bits 0-15) and reset (16-31).
    pub const SET: Option<usize> = Some(0x18);
    pub const BIT: u32 = 1 << 12;
}

impl AlarmPin {
    /// The pin, at its alarm level.
    pub fn new() -> Self {
        let r = Regs(pin::BASE);
        #[cfg(feature = "board-stm32f4")]
        r.write(
            pin::MODER,
            (r.read(pin::MODER) & !(0b11 << 24)) | (0b01 << 24),
        );
        let mut p = AlarmPin(r);
        let _ = embedded_hal::digital::OutputPin::set_low(&mut p);
        p
    }
    fn level(&mut self, high: bool) {
        match pin::SET {
            Some(bsrr) => self
                .0
                .write(bsrr, if high { pin::BIT } else { pin::BIT << 16 }),
            None => {
                let v = self.0.read(pin::OUT);
                self.0
                    .write(pin::OUT, if high { v | pin::BIT } else { v & !pin::BIT });
            }
        }
    }
}

impl embedded_hal::digital::ErrorType for AlarmPin {
    type Error = Infallible;
}

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

impl embedded_hal::digital::StatefulOutputPin for AlarmPin {
    fn is_set_high(&mut self) -> Result<bool, Infallible> {
        Ok(self.0.read(pin::OUT) & pin::BIT != 0)
    }
    fn is_set_low(&mut self) -> Result<bool, Infallible> {
        Ok(self.0.read(pin::OUT) & pin::BIT == 0)
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
