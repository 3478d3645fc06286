//! Everything board-specific, in one module: the two UARTs (behind
//! `embedded_io::{Read, Write}`, so a HAL's UART can replace them), the tick
//! counter, and how to stop after a fatal error.
//!
//! - `board-qemu` (default, CI): QEMU's `mps2-an386`, a Cortex-M4 with CMSDK
//!   APB UARTs: UART0 (0x4000_4000) is the frame link, UART1 (0x4000_5000)
//!   the NMEA output.
//! - `board-stm32f4`: an STM32F407-class part at its 16 MHz reset clock:
//!   USART2 (PA2/PA3) is the link, USART3 (PB10/PB11) the NMEA output, both
//!   115200 8N1.

use core::convert::Infallible;
use core::ptr::{read_volatile, write_volatile};

use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::SYST;

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

    /// CMSDK APB UART (ARM DDI 0479C §4.3).
    pub struct Uart(Regs, u32);

    const DATA: usize = 0x00;
    const STATE: usize = 0x04;
    const CTRL: usize = 0x08;
    const BAUDDIV: usize = 0x10;
    const INTSTATUS: usize = 0x0C;
    const STATE_TX_FULL: u32 = 1 << 0;
    const STATE_RX_FULL: u32 = 1 << 1;
    const CTRL_TX_EN: u32 = 1 << 0;
    const CTRL_RX_EN: u32 = 1 << 1;
    const CTRL_RX_INTEN: u32 = 1 << 3;
    const INTSTATUS_RX: u32 = 1 << 1;
    /// NVIC set-enable and clear-pending registers for IRQs 0-31.
    const NVIC_ISER0: usize = 0xE000_E100;
    const NVIC_ICPR0: usize = 0xE000_E280;
    /// 25 MHz / 115200 baud.
    const BAUDDIV_115200: u32 = 217;

    pub const UART0: usize = 0x4000_4000;
    pub const UART1: usize = 0x4000_5000;

    impl Uart {
        /// # Safety
        /// `base` is a CMSDK UART of this machine, owned by nobody else.
        /// `rx_irq`: the UART's RX interrupt line (UART0: 0, UART1: 2).
        /// With interrupts masked (PRIMASK), the pending RX interrupt only
        /// wakes the core from WFI; no handler runs.
        pub unsafe fn new(base: usize, rx_irq: u32) -> Self {
            let r = Regs(base);
            r.write(BAUDDIV, BAUDDIV_115200);
            r.write(CTRL, CTRL_TX_EN | CTRL_RX_EN | CTRL_RX_INTEN);
            Regs(NVIC_ISER0).write(0, 1 << rx_irq);
            Uart(r, rx_irq)
        }
        pub fn rx_ready(&self) -> bool {
            self.0.read(STATE) & STATE_RX_FULL != 0
        }
        pub fn tx_ready(&self) -> bool {
            self.0.read(STATE) & STATE_TX_FULL == 0
        }
        /// Sleeps (WFI) until a byte is there instead of polling: a polling
        /// core keeps QEMU's device lock busy and halves the rate at which
        /// QEMU delivers bytes (15-20 kB/s polling, 27-37 kB/s with WFI:
        /// host-tests/examples/qemu_throughput.rs).
        pub fn read_byte(&mut self) -> u8 {
            loop {
                if self.rx_ready() {
                    return self.0.read(DATA) as u8;
                }
                self.0.write(INTSTATUS, INTSTATUS_RX);
                Regs(NVIC_ICPR0).write(0, 1 << self.1);
                if self.rx_ready() {
                    return self.0.read(DATA) as u8;
                }
                crate::watchdog::on_idle();
                cortex_m::asm::wfi();
            }
        }
        pub fn write_byte(&mut self, b: u8) {
            while !self.tx_ready() {}
            self.0.write(DATA, u32::from(b));
        }
    }
}

#[cfg(feature = "board-stm32f4")]
mod uart {
    use super::Regs;

    /// STM32F4 USART (RM0090 §30.6), polled.
    pub struct Uart(Regs);

    const SR: usize = 0x00;
    const DR: usize = 0x04;
    const BRR: usize = 0x08;
    const CR1: usize = 0x0C;
    const SR_RXNE: u32 = 1 << 5;
    const SR_TXE: u32 = 1 << 7;
    const SR_ORE: u32 = 1 << 3;
    const CR1_UE: u32 = 1 << 13;
    const CR1_TE: u32 = 1 << 3;
    const CR1_RE: u32 = 1 << 2;
    /// 16 MHz HSI / 115200 = 138.9 -> mantissa 8, fraction 11 (0x8B).
    const BRR_115200_AT_16MHZ: u32 = 0x8B;

    pub const USART2: usize = 0x4000_4400;
    pub const USART3: usize = 0x4000_4800;
    const RCC: usize = 0x4002_3800;
    const RCC_AHB1ENR: usize = 0x30;
    const RCC_APB1ENR: usize = 0x40;
    const GPIOA: usize = 0x4002_0000;
    const GPIOB: usize = 0x4002_0400;
    const MODER: usize = 0x00;
    const AFRL: usize = 0x20;
    const AFRH: usize = 0x24;

    /// Clocks and pins: GPIOA/B, USART2/3; PA2/PA3 and PB10/PB11 to AF7.
    pub fn init_pins() {
        let rcc = Regs(RCC);
        rcc.write(RCC_AHB1ENR, rcc.read(RCC_AHB1ENR) | 0b11);
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
        pub unsafe fn new(base: usize) -> Self {
            let r = Regs(base);
            r.write(BRR, BRR_115200_AT_16MHZ);
            r.write(CR1, CR1_UE | CR1_TE | CR1_RE);
            Uart(r)
        }
        pub fn rx_ready(&self) -> bool {
            self.0.read(SR) & (SR_RXNE | SR_ORE) != 0
        }
        pub fn tx_ready(&self) -> bool {
            self.0.read(SR) & SR_TXE != 0
        }
        pub fn read_byte(&mut self) -> u8 {
            while !self.rx_ready() {
                crate::watchdog::on_idle();
            }
            // Reading DR clears RXNE and an overrun; a lost byte shows up as
            // a bad frame, which is answered.
            self.0.read(DR) as u8
        }
        pub fn write_byte(&mut self, b: u8) {
            while !self.tx_ready() {}
            self.0.write(DR, u32::from(b));
        }
    }
}

pub use uart::Uart;

impl embedded_io::ErrorType for Uart {
    type Error = Infallible;
}

impl embedded_io::Read for Uart {
    /// Blocks for the first byte, then takes what is already there.
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Infallible> {
        let mut n = 0;
        for slot in buf.iter_mut() {
            if n > 0 && !self.rx_ready() {
                break;
            }
            *slot = self.read_byte();
            n += 1;
        }
        Ok(n)
    }
}

impl embedded_io::ReadReady for Uart {
    fn read_ready(&mut self) -> Result<bool, Infallible> {
        Ok(self.rx_ready())
    }
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

/// The link UART and the NMEA UART.
pub fn uarts() -> (Uart, Uart) {
    #[cfg(feature = "board-qemu")]
    // SAFETY: called once from `main`; UART0/UART1 are used nowhere else.
    unsafe {
        cortex_m::interrupt::disable();
        (Uart::new(uart::UART0, 0), Uart::new(uart::UART1, 2))
    }
    #[cfg(feature = "board-stm32f4")]
    // SAFETY: called once from `main`; USART2/USART3 are used nowhere else.
    unsafe {
        uart::init_pins();
        (Uart::new(uart::USART2), Uart::new(uart::USART3))
    }
}

/// SysTick as a free-running 24-bit counter at the core clock.
pub struct Ticks(SYST);

impl Ticks {
    pub fn new(mut syst: SYST) -> Self {
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(0x00FF_FFFF);
        syst.clear_current();
        syst.enable_counter();
        Ticks(syst)
    }
    /// Counts up (SysTick counts down).
    pub fn now(&self) -> u32 {
        0x00FF_FFFF - SYST::get_current()
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
