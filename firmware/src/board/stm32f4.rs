//! The STM32F405/407 board on `stm32f4xx-hal` (embedded-hal 1.0,
//! embedded-io 0.6): the HAL sets up the pins, the USARTs, the alarm pin
//! and the IWDG; this module adapts the HAL's non-blocking transmitter to
//! `embedded_io::Write` and its receiver to [`LinkRxPort`].
//!
//! USART2 (PA2/PA3) is the link, USART3 TX (PB10) the NMEA output, both
//! 115200 8N1; PD12 (the green LED of an STM32F4-Discovery) the alarm pin.
//! The core runs at the 16 MHz HSI the part resets to: `constrain`
//! configures nothing, so nothing waits for a ready bit (QEMU's
//! netduinoplus2, an STM32F405, does not model the RCC; docs/SAFETY.md).

use stm32f4xx_hal::gpio::{Output, PushPull, PD12};
use stm32f4xx_hal::pac;
use stm32f4xx_hal::prelude::*;
use stm32f4xx_hal::serial::{self, RxISR, RxListen, Serial};
use stm32f4xx_hal::watchdog::IndependentWatchdog;

use super::{Board, HardwareReset, LinkRxPort, Parts, Watchdog};

/// The board.
pub struct Stm32f4;

/// The 16 MHz HSI the part resets to.
const CORE_HZ: u32 = 16_000_000;

impl Board for Stm32f4 {
    type Link = Uart<pac::USART2>;
    type Nmea = Uart<pac::USART3>;
    type LinkRx = RxPort;
    type Alarm = AlarmPin;
    type Watchdog = Iwdg;
    /// USART2's interrupt (RM0090 Table 61, position 38).
    const LINK_RX_IRQ: u16 = pac::Interrupt::USART2 as u16;

    fn take() -> Option<Parts<Self>> {
        cortex_m::interrupt::disable();
        let dp = pac::Peripherals::take()?;
        let reset = reset_cause(&dp.RCC);
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
        Some(Parts {
            link: Uart(link_tx),
            link_rx: RxPort(link_rx),
            nmea: Uart(nmea),
            alarm,
            watchdog: Iwdg(IndependentWatchdog::new(dp.IWDG)),
            core_hz: CORE_HZ,
            reset,
        })
    }
}

/// RCC_CSR's reset flags (RM0090 §7.3.21), then cleared (RMVF) so that the
/// next reset reports only its own cause.
fn reset_cause(rcc: &pac::RCC) -> HardwareReset {
    let csr = rcc.csr().read();
    let cause = if csr.porrstf().bit_is_set() || csr.borrstf().bit_is_set() {
        HardwareReset::PowerOn
    } else if csr.wdgrstf().bit_is_set() {
        HardwareReset::Watchdog
    } else {
        HardwareReset::Other
    };
    rcc.csr().modify(|_, w| w.rmvf().set_bit());
    cause
}

/// A USART's transmit side (blocking `embedded_io::Write`).
pub struct Uart<U: serial::Instance>(serial::Tx<U, u8>);
/// The link USART's receive side, driven by its RXNE interrupt.
pub struct RxPort(serial::Rx<pac::USART2, u8>);
/// PD12, push-pull; the HAL's pin implements embedded-hal's `OutputPin`
/// and `StatefulOutputPin`.
pub type AlarmPin = PD12<Output<PushPull>>;

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

impl LinkRxPort for RxPort {
    fn rx_ready(&self) -> bool {
        self.0.is_rx_not_empty()
    }
    /// A lost byte: an overrun, or a framing, parity or noise error (the
    /// HAL reads the data register to clear them and drops the byte).
    fn read(&mut self) -> (Option<u8>, bool) {
        match embedded_hal_nb::serial::Read::read(&mut self.0) {
            Ok(b) => (Some(b), false),
            Err(nb::Error::WouldBlock) => (None, false),
            Err(nb::Error::Other(_)) => (None, true),
        }
    }
    /// RXNE clears when the data register is read.
    fn ack(&mut self) {}
    fn set_irq(&mut self, on: bool) {
        if on {
            self.0.listen()
        } else {
            self.0.unlisten()
        }
    }
}

/// The independent watchdog, through the HAL (LSI clock, nominally
/// 32 kHz; its datasheet range and the margin it leaves: docs/SAFETY.md).
pub struct Iwdg(IndependentWatchdog);

impl Watchdog for Iwdg {
    const TIMEOUT_MS: u32 = 2_000;
    fn start(&mut self) {
        self.0.start(Self::TIMEOUT_MS.millis());
    }
    fn feed(&mut self) {
        self.0.feed();
    }
}
