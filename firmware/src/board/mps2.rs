//! QEMU's `mps2-an386` (Cortex-M4, CI's board) on a small register layer:
//! CMSDK APB UARTs (UART0 at 0x4000_4000 the frame link, UART1 at
//! 0x4000_5000 the NMEA output), the CMSDK APB watchdog and the FPGA I/O
//! block's LED0 as the alarm pin. It has no HAL and no reset-cause
//! register; its core clock is a fixed 25 MHz.

use core::convert::Infallible;
use core::ptr::{read_volatile, write_volatile};
use core::sync::atomic::{AtomicBool, Ordering};

use super::{Board, HardwareReset, LinkRxPort, Parts, Watchdog};

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

/// The board.
pub struct Mps2An386;

/// The core clock, Hz (QEMU's model of the board).
const CORE_HZ: u32 = 25_000_000;

impl Board for Mps2An386 {
    type Link = Uart;
    type Nmea = Uart;
    type LinkRx = RxPort;
    type Alarm = AlarmPin;
    type Watchdog = CmsdkWatchdog;
    /// UART0's RX interrupt line on mps2-an385/an386 (QEMU `hw/arm/mps2.c`:
    /// RX lines 0, 2, 4, 18, 20 for UART0-4; TX one above each).
    const LINK_RX_IRQ: u16 = 0;

    /// LED0's bit cleared (read-modify-write of the FPGA I/O register:
    /// should the main loop's own write of the pin interleave, it writes
    /// the level its monitor decided, which after the deadline is the
    /// alarm level too).
    fn force_alarm() {
        let r = Regs(FPGAIO);
        r.write(LED0, r.read(LED0) & !LED0_BIT);
    }

    /// The AN386 image has no unique ID: the provisioned unit ID is the
    /// unit's identity.
    fn unique_id() -> Option<[u32; 3]> {
        None
    }

    fn take() -> Option<Parts<Self>> {
        static TAKEN: AtomicBool = AtomicBool::new(false);
        cortex_m::interrupt::disable();
        if TAKEN.swap(true, Ordering::Relaxed) {
            return None;
        }
        // SAFETY: taken once (above); UART0/UART1 are used nowhere else.
        let (link, nmea) = unsafe { (Uart::new(UART0, true), Uart::new(UART1, false)) };
        let link_rx = RxPort(link.0);
        Some(Parts {
            link,
            link_rx,
            nmea,
            alarm: AlarmPin::new(),
            watchdog: CmsdkWatchdog(Regs(WDOG)),
            core_hz: CORE_HZ,
            clock_fallback: false,
            // The AN386 image has no random number generator.
            hardware_entropy: None,
            reset: HardwareReset::Other,
        })
    }
}

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

const UART0: usize = 0x4000_4000;
const UART1: usize = 0x4000_5000;

impl Uart {
    /// # Safety
    /// `base` is a CMSDK UART of this machine, owned by nobody else.
    /// With `rx`, reception and its interrupt are enabled too.
    unsafe fn new(base: usize, rx: bool) -> Self {
        let r = Regs(base);
        r.write(BAUDDIV, BAUDDIV_115200);
        let rx_bits = if rx { CTRL_RX_EN | CTRL_RX_INTEN } else { 0 };
        r.write(CTRL, CTRL_TX_EN | rx_bits);
        Uart(r)
    }
    fn tx_ready(&self) -> bool {
        self.0.read(STATE) & STATE_TX_FULL == 0
    }
    fn write_byte(&mut self, b: u8) {
        while !self.tx_ready() {}
        self.0.write(DATA, u32::from(b));
    }
}

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

impl LinkRxPort for RxPort {
    fn rx_ready(&self) -> bool {
        self.0.read(STATE) & STATE_RX_FULL != 0
    }
    fn read(&mut self) -> (Option<u8>, bool) {
        let overrun = self.0.read(STATE) & STATE_RX_OVERRUN != 0;
        if overrun {
            self.0.write(STATE, STATE_RX_OVERRUN);
        }
        (Some(self.0.read(DATA) as u8), overrun)
    }
    /// Write-one-to-clear.
    fn ack(&mut self) {
        self.0.write(INTSTATUS, INTSTATUS_RX);
    }
    fn set_irq(&mut self, on: bool) {
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

/// The CMSDK APB watchdog (0x4000_8000, WDOGCLK 25 MHz, ARM DDI 0479C
/// §4.4), interrupt on NMI. Its first expiry raises the NMI, whose handler
/// records `Watchdog` and resets (`main.rs`); the second (RESEN) resets in
/// hardware should the handler not run.
pub struct CmsdkWatchdog(Regs);

const WDOG: usize = 0x4000_8000;
const WDOG_LOAD: usize = 0x00;
const WDOG_CTRL: usize = 0x08;
const WDOG_INTCLR: usize = 0x0C;
const WDOG_LOCK: usize = 0xC00;
const WDOG_UNLOCK_KEY: u32 = 0x1ACC_E551;
const WDOG_CTRL_INTEN: u32 = 1 << 0;
const WDOG_CTRL_RESEN: u32 = 1 << 1;

/// 2 s: the CMSDK watchdog counts the 25 MHz core clock, which has no
/// tolerance to speak of under QEMU.
const WATCHDOG_TIMEOUT_MS: u32 = 2_000;

impl Watchdog for CmsdkWatchdog {
    fn timeout_ms(&self) -> u32 {
        WATCHDOG_TIMEOUT_MS
    }
    fn start(&mut self) {
        let load = CORE_HZ / 1_000 * WATCHDOG_TIMEOUT_MS;
        self.0.write(WDOG_LOCK, WDOG_UNLOCK_KEY);
        self.0.write(WDOG_LOAD, load);
        self.0.write(WDOG_CTRL, WDOG_CTRL_INTEN | WDOG_CTRL_RESEN);
        self.0.write(WDOG_LOCK, 0);
    }
    fn feed(&mut self) {
        self.0.write(WDOG_LOCK, WDOG_UNLOCK_KEY);
        self.0.write(WDOG_INTCLR, 1);
        self.0.write(WDOG_LOCK, 0);
    }
}

/// The integrity-alarm discrete output, behind embedded-hal 1.0's
/// `OutputPin` and `StatefulOutputPin` (read back from the register).
/// Active low on every board: the pin is driven high only while integrity
/// is assured, so a unit that stops, resets or loses power shows the alarm
/// (docs/SAFETY.md).
///
/// The FPGA I/O block of mps2-an385/an386 (0x4002_8000, register LED0 at
/// offset 0, bit 0: the first user LED; QEMU `hw/misc/mps2-fpgaio.c`).
pub struct AlarmPin(Regs);

const FPGAIO: usize = 0x4002_8000;
/// LED0: written and read back.
const LED0: usize = 0x00;
const LED0_BIT: u32 = 1 << 0;

impl AlarmPin {
    /// The pin, at its alarm level.
    fn new() -> Self {
        let mut p = AlarmPin(Regs(FPGAIO));
        p.level(false);
        p
    }
    fn level(&mut self, high: bool) {
        let v = self.0.read(LED0);
        self.0
            .write(LED0, if high { v | LED0_BIT } else { v & !LED0_BIT });
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
        Ok(self.0.read(LED0) & LED0_BIT != 0)
    }
    fn is_set_low(&mut self) -> Result<bool, Infallible> {
        Ok(self.0.read(LED0) & LED0_BIT == 0)
    }
}
