//! The STM32F405/407 board on `stm32f4xx-hal` (embedded-hal 1.0,
//! embedded-io 0.6): the HAL sets up the pins, the USARTs, the alarm pin
//! and the IWDG; this module adapts the HAL's non-blocking transmitter to
//! `embedded_io::Write` and its receiver to [`LinkRxPort`].
//!
//! USART2 (PA2/PA3) is the link, USART3 TX (PB10) the NMEA output, both
//! 115200 8N1; PD12 (the green LED of an STM32F4-Discovery) the alarm pin.
//!
//! The core runs at 168 MHz from the 8 MHz HSE through the main PLL
//! ([`start_clocks`]), every ready-bit wait bounded by an iteration budget;
//! if a wait runs out the part stays on the 16 MHz HSI it resets to, and
//! says so ([`Parts::clock_fallback`], `Status.clock_fallback`). QEMU's
//! netduinoplus2 (an STM32F405) leaves the RCC unimplemented (its registers
//! read 0), so there HSERDY never sets and the fallback is the path CI runs
//! (docs/SAFETY.md "Clocks").
//!
//! The boot entropy's hardware part is the RNG, clocked by the main PLL's
//! 48 MHz output (PLL48CLK): [`hardware_entropy`], the draw itself in
//! `rng_draw`. QEMU's netduinoplus2 does not model the RNG (its registers
//! read 0, DRDY never sets) and its PLL never locks, so there the boot has
//! no hardware entropy, which `Status.hardware_entropy` shows.

use stm32f4xx_hal::gpio::{Output, PushPull, PD12};
use stm32f4xx_hal::pac;
use stm32f4xx_hal::prelude::*;
use stm32f4xx_hal::rcc::{self, Rcc};
use stm32f4xx_hal::serial::{self, RxISR, RxListen, Serial};
use stm32f4xx_hal::watchdog::IndependentWatchdog;

use super::rng_draw::{self, RngRegs};
use super::{Board, HardwareReset, LinkRxPort, Parts, Watchdog};

/// The board.
pub struct Stm32f4;

/// The HSE crystal: 8 MHz on the STM32F4-Discovery.
const HSE_HZ: u32 = 8_000_000;
/// The core clock from the PLL: the part's maximum (STM32F405/407
/// datasheet, f_HCLK max 168 MHz).
const PLL_SYSCLK_HZ: u32 = 168_000_000;
/// APB1 (USART2, USART3) at its 42 MHz maximum, APB2 at its 84 MHz.
const PCLK1_HZ: u32 = 42_000_000;
const PCLK2_HZ: u32 = 84_000_000;
/// The main PLL for 168 MHz from 8 MHz (RM0090 §7.3.2): VCO input
/// 8 MHz / M = 2 MHz (the jitter-minimising input), VCO 2 MHz x N =
/// 336 MHz, SYSCLK = VCO / 2, the 48 MHz domain VCO / Q = 48 MHz. The
/// values `stm32f4xx-hal`'s `freeze` derives for the same request (it
/// writes them again, unchanged, while the PLL already runs).
const PLL_M: u8 = 4;
const PLL_N: u16 = 168;
const PLL_Q: u8 = 7;
const _: () = {
    let vco_hz = HSE_HZ / PLL_M as u32 * PLL_N as u32;
    assert!(vco_hz / 2 == PLL_SYSCLK_HZ);
    assert!(vco_hz / PLL_Q as u32 == 48_000_000);
    assert!(PLL_SYSCLK_HZ / PCLK1_HZ == 4 && PLL_SYSCLK_HZ / PCLK2_HZ == 2);
};
/// The HSI's frequency at its datasheet maximum (16 MHz + 4.5 %, the
/// factory-calibrated accuracy over -40..105 °C, STM32F405/407 datasheet
/// "HSI oscillator characteristics"): the fastest the wait loops can spin.
const HSI_MAX_HZ: u32 = 16_720_000;
/// Time granted to the HSE crystal to start: 10 x its 2 ms typical start-up
/// (datasheet "HSE 4-26 MHz oscillator characteristics", t_SU(HSE)).
const HSE_START_BUDGET_US: u32 = 20_000;
/// Time granted to the PLL to lock: 3 x its 300 us maximum lock time
/// (datasheet "Main PLL characteristics", t_LOCK at VCO 432 MHz).
const PLL_LOCK_BUDGET_US: u32 = 900;
/// Time granted to a register write to show (the flash latency read-back,
/// the clock switch's SWS): a few AHB cycles on the part; 10 us.
const REGISTER_BUDGET_US: u32 = 10;

/// Loop iterations that last at least `budget_us` on the HSI: one
/// iteration takes at least one cycle (a volatile read, a test and a
/// branch take more) of at most 1 / [`HSI_MAX_HZ`]. An iteration takes at
/// most ~10 cycles (an AHB read and the loop), so a wait that runs out
/// lasts at most ~11 x `budget_us` at the HSI's slowest (-8 %): 0.23 s
/// for the HSE.
const fn iterations(budget_us: u32) -> u32 {
    iterations_at(HSI_MAX_HZ, budget_us)
}

/// Loop iterations that last at least `budget_us` on a core clock of at
/// most `core_max_hz` (one iteration, at least one cycle).
const fn iterations_at(core_max_hz: u32, budget_us: u32) -> u32 {
    (core_max_hz as u64 * budget_us as u64 / 1_000_000) as u32
}

/// The main PLL from the HSI for PLL48CLK alone, on the HSI fallback
/// (RM0090 §7.3.2): VCO input 16 MHz / M = 2 MHz, VCO x N = 336 MHz,
/// PLL48CLK = VCO / Q = 48 MHz (the RNG's clock); its P output (168 MHz)
/// drives nothing, SYSCLK stays on the HSI.
const PLL_M_HSI: u8 = 8;
const HSI_HZ: u32 = 16_000_000;
const _: () = {
    let vco_hz = HSI_HZ / PLL_M_HSI as u32 * PLL_N as u32;
    assert!(vco_hz / PLL_Q as u32 == 48_000_000);
};
/// Time granted to the RNG for one word: 120 x the 40 PLL48CLK periods
/// (0.83 us at 48 MHz) it takes to make one (RM0090 §24.3.1).
const RNG_WORD_BUDGET_US: u32 = 100;

/// The RNG's registers (RM0090 §24.4) for the draw.
struct Rng<'a>(&'a pac::RNG);

impl RngRegs for Rng<'_> {
    fn status(&mut self) -> u32 {
        self.0.sr().read().bits()
    }
    fn data(&mut self) -> u32 {
        self.0.dr().read().bits()
    }
    fn set_enabled(&mut self, on: bool) {
        self.0.cr().modify(|_, w| w.rngen().bit(on));
    }
    fn clear_errors(&mut self) {
        self.0.sr().modify(|_, w| {
            w.seis().clear();
            w.ceis().clear()
        });
    }
}

/// 32 bytes from the RNG, or `None` if it could not give them without
/// error within its budget (`rng_draw::draw`). Its clock, PLL48CLK: on the
/// PLL path the main PLL already makes 48 MHz (`PLL_Q` from the HSE); on
/// the HSI fallback the PLL, off, is started from the HSI for it
/// ([`PLL_M_HSI`]) with a bounded wait on PLLRDY, and stopped again after
/// the draw. The RNG and its bus clock are switched off afterwards.
fn hardware_entropy(rcc: &Rcc, rng: &pac::RNG, clock: ClockStart) -> Option<[u8; 32]> {
    let core_max_hz = if clock == ClockStart::Pll {
        PLL_SYSCLK_HZ
    } else {
        if rcc.cr().read().pllon().bit_is_set() {
            return None;
        }
        rcc.pllcfgr().write(|w| {
            w.pllsrc().hsi();
            w.pllp().div2();
            // SAFETY: M in 2..=63, N in 50..=432, Q in 2..=15 (RM0090 §7.3.2).
            unsafe {
                w.pllm().bits(PLL_M_HSI);
                w.plln().bits(PLL_N);
                w.pllq().bits(PLL_Q)
            }
        });
        rcc.cr().modify(|_, w| w.pllon().set_bit());
        HSI_MAX_HZ
    };
    let locked = wait_until(iterations_at(core_max_hz, PLL_LOCK_BUDGET_US), || {
        rcc.cr().read().pllrdy().bit_is_set()
    });
    let drawn = if locked {
        rcc.ahb2enr().modify(|_, w| w.rngen().set_bit());
        // The enable reaches the peripheral before its first access.
        cortex_m::asm::dsb();
        let drawn = rng_draw::draw(
            &mut Rng(rng),
            iterations_at(core_max_hz, RNG_WORD_BUDGET_US),
        );
        rcc.ahb2enr().modify(|_, w| w.rngen().clear_bit());
        drawn
    } else {
        None
    };
    if clock != ClockStart::Pll {
        rcc.cr().modify(|_, w| w.pllon().clear_bit());
    }
    drawn
}

/// Spins until `ready` or `budget` iterations have passed; true if ready.
fn wait_until(budget: u32, mut ready: impl FnMut() -> bool) -> bool {
    for _ in 0..budget {
        if ready() {
            return true;
        }
    }
    ready()
}

/// Which clock drives the core, and why.
#[derive(Clone, Copy, PartialEq, Eq, defmt::Format)]
pub enum ClockStart {
    /// 168 MHz from the HSE through the PLL.
    Pll,
    /// The flash latency did not read back: stayed on the HSI.
    FlashLatency,
    /// HSERDY did not set within its budget: stayed on the HSI.
    HseTimeout,
    /// PLLRDY did not set within its budget: stayed on the HSI.
    PllTimeout,
    /// SWS did not show the PLL after the switch: back on the HSI.
    SwitchTimeout,
}

/// The clock tree: 168 MHz from the HSE through the PLL, flash at 5 wait
/// states with the ART accelerator (prefetch, instruction and data
/// caches), APB1 at 42 MHz, APB2 at 84 MHz (RM0090 §3.5.1, §7.2), every
/// ready bit waited on for a bounded number of iterations. The HSE and the
/// PLL are brought up here, with bounded waits, before `stm32f4xx-hal`'s
/// `freeze` is asked for the same configuration: its own (unbounded) waits
/// then find HSERDY and PLLRDY already set, and the `Rcc` it returns
/// carries the clocks the USARTs' baud rates are computed from. If a wait
/// runs out, the part stays on (or returns to) the HSI at 16 MHz with 0
/// wait states, the HSE and the PLL off ([`hsi_fallback`]). `None` when
/// the clock the core runs on is unknown (SWS shows neither the PLL nor,
/// after the way back, the HSI).
fn start_clocks(rcc: pac::RCC, flash: &pac::FLASH) -> Option<(Rcc, ClockStart)> {
    let rcc = rcc.constrain();
    let outcome = start_pll(&rcc, flash);
    if outcome != ClockStart::Pll {
        return Some((hsi_fallback(rcc)?, outcome));
    }
    let config = rcc::Config::hse(HSE_HZ.Hz())
        .sysclk(PLL_SYSCLK_HZ.Hz())
        .pclk1(PCLK1_HZ.Hz())
        .pclk2(PCLK2_HZ.Hz());
    let rcc = rcc.freeze(config);
    if !wait_until(iterations(REGISTER_BUDGET_US), || {
        rcc.cfgr().read().sws().is_pll()
    }) {
        return Some((hsi_fallback(rcc)?, ClockStart::SwitchTimeout));
    }
    Some((rcc, ClockStart::Pll))
}

/// HSE on, PLL configured and locked, flash latency at 5 wait states with
/// the ART on, each within its budget; SYSCLK still on the HSI.
fn start_pll(rcc: &pac::RCC, flash: &pac::FLASH) -> ClockStart {
    rcc.cr().modify(|_, w| w.hseon().set_bit());
    if !wait_until(iterations(HSE_START_BUDGET_US), || {
        rcc.cr().read().hserdy().bit_is_set()
    }) {
        return ClockStart::HseTimeout;
    }
    rcc.pllcfgr().write(|w| {
        w.pllsrc().hse();
        w.pllp().div2();
        // SAFETY: M in 2..=63, N in 50..=432, Q in 2..=15 (RM0090 §7.3.2).
        unsafe {
            w.pllm().bits(PLL_M);
            w.plln().bits(PLL_N);
            w.pllq().bits(PLL_Q)
        }
    });
    rcc.cr().modify(|_, w| w.pllon().set_bit());
    if !wait_until(iterations(PLL_LOCK_BUDGET_US), || {
        rcc.cr().read().pllrdy().bit_is_set()
    }) {
        return ClockStart::PllTimeout;
    }
    // The wait states before the faster clock, read back before the switch
    // (RM0090 §3.5.1, "Increasing the CPU frequency").
    flash.acr().modify(|_, w| {
        // 5 wait states at 168 MHz and 2.7-3.6 V (RM0090 Table 10:
        // 150 < HCLK <= 168 MHz).
        w.latency().ws5();
        w.prften().set_bit();
        w.icen().set_bit();
        w.dcen().set_bit()
    });
    if !wait_until(iterations(REGISTER_BUDGET_US), || {
        flash.acr().read().latency().is_ws5()
    }) {
        return ClockStart::FlashLatency;
    }
    ClockStart::Pll
}

/// Back to the HSI: SYSCLK on the HSI (waited for within its budget; the
/// PLL cannot be stopped while it drives the core), the PLL and the HSE
/// off, then the HAL's `Config::hsi()` (prescalers 1, flash at 0 wait
/// states, ART on), which waits on no ready bit. `None` if SWS does not
/// show the HSI: the core may still run fast, so the wait states are left
/// as they are and the board does not start.
fn hsi_fallback(rcc: Rcc) -> Option<Rcc> {
    rcc.cfgr().modify(|_, w| w.sw().hsi());
    if !wait_until(iterations(REGISTER_BUDGET_US), || {
        rcc.cfgr().read().sws().is_hsi()
    }) {
        return None;
    }
    rcc.cr().modify(|_, w| w.pllon().clear_bit());
    rcc.cr().modify(|_, w| w.hseon().clear_bit());
    Some(rcc.freeze(rcc::Config::hsi()))
}

impl Board for Stm32f4 {
    /// PD12 reset through GPIOD_BSRR (RM0090 §8.4.7: a write of 1 to
    /// BR12 drives the pin low, atomically, whatever the other bits).
    fn force_alarm() {
        const GPIOD_BSRR: usize = 0x4002_0C00 + 0x18;
        // SAFETY: GPIOD's bit set/reset register, always mapped; writing
        // BR12 alone changes PD12's output only (the pin the HAL set up as
        // the alarm output), and only to the alarm level.
        unsafe { core::ptr::write_volatile(GPIOD_BSRR as *mut u32, 1 << (16 + 12)) }
    }
    /// The 96-bit unique device ID (RM0090 §39.1: three words at
    /// 0x1FFF_7A10, factory-programmed, read-only). QEMU's netduinoplus2
    /// does not map that region (a read would be a bus fault), so its
    /// build has none and uses the provisioned unit ID alone.
    fn unique_id() -> Option<[u32; 3]> {
        if cfg!(feature = "qemu-netduinoplus2") {
            return None;
        }
        const UID: usize = 0x1FFF_7A10;
        // SAFETY: the unique ID's three aligned words, mapped on every
        // STM32F405/407 (RM0090 §39.1); plain reads.
        Some(core::array::from_fn(|k| unsafe {
            core::ptr::read_volatile((UID + 4 * k) as *const u32)
        }))
    }
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
        let (mut rcc, clock) = start_clocks(dp.RCC, &dp.FLASH)?;
        let core_hz = rcc.clocks.hclk().raw();
        defmt::info!("clock: {} at {=u32} Hz", clock, core_hz);
        let hardware_entropy = hardware_entropy(&rcc, &dp.RNG, clock);
        defmt::info!("hardware entropy: {=bool}", hardware_entropy.is_some());
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
            watchdog: Iwdg {
                iwdg: IndependentWatchdog::new(dp.IWDG),
                timeout_ms: if clock == ClockStart::Pll {
                    IWDG_TIMEOUT_PLL_MS
                } else {
                    IWDG_TIMEOUT_HSI_MS
                },
            },
            core_hz,
            clock_fallback: clock != ClockStart::Pll,
            reset,
            hardware_entropy,
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

/// The IWDG's nominal timeout at 168 MHz. The HAL programs prescaler /256
/// and reload 624: 625 x 256 / f_LSI, 3.40 s at the LSI's datasheet
/// maximum of 47 kHz, 5.0 s at its nominal 32 kHz, 9.41 s at its minimum
/// of 17 kHz. Half the shortest, less the longest blocking answer and NMEA
/// burst at 115200 baud (0.45 s), leaves 26.2 M guest instructions at 8
/// cycles each (5 flash wait states, every line missing the ART), above
/// the costliest measured epoch (docs/SAFETY.md "Watchdog margin").
pub const IWDG_TIMEOUT_PLL_MS: u32 = 5_000;
/// The IWDG's nominal timeout on the 16 MHz HSI fallback: prescaler /256,
/// reload 1874, 10.2 s at 47 kHz (28.2 s at 17 kHz), leaving 24.8 M
/// instructions at 3 cycles each (0 wait states); at the 168 MHz timeout
/// the costliest epoch would take 3.3 s, over half of 3.40 s.
pub const IWDG_TIMEOUT_HSI_MS: u32 = 15_000;

/// The independent watchdog, through the HAL (LSI clock, nominally
/// 32 kHz), with the timeout for the clock the core runs at: set once the
/// clock is known.
pub struct Iwdg {
    iwdg: IndependentWatchdog,
    timeout_ms: u32,
}

impl Watchdog for Iwdg {
    fn timeout_ms(&self) -> u32 {
        self.timeout_ms
    }
    /// The HAL asserts a timeout under 2^15 ms; both of this board's
    /// timeouts are (checked at compile time below), and the clamp, the
    /// identity on them, lets the build drop the assertion's panic path.
    fn start(&mut self) {
        const IWDG_MAX_MS: u32 = (1 << 15) - 1;
        const {
            assert!(IWDG_TIMEOUT_PLL_MS <= IWDG_MAX_MS && IWDG_TIMEOUT_HSI_MS <= IWDG_MAX_MS);
        }
        self.iwdg.start(self.timeout_ms.min(IWDG_MAX_MS).millis());
    }
    fn feed(&mut self) {
        self.iwdg.feed();
    }
}
