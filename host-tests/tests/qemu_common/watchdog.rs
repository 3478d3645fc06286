//! The watchdog budget of the STM32F4 build under QEMU's netduinoplus2
//! (`-icount shift=0`): the clock and IWDG constants, the budget in guest
//! instructions per epoch, and one epoch's count. Shared by
//! `tests/qemu_watchdog_margin.rs` and `examples/worst_case_search.rs`;
//! docs/SAFETY.md "Watchdog margin".

#![allow(dead_code)]

use raim_proto::message::{CommandRef, ResponseBody};
use raim_qemu::{Machine, Options, QemuSession};

/// The clock QEMU's netduinoplus2 model feeds the core and SysTick
/// (`hw/arm/netduinoplus2.c`, SYSCLK_FRQ), whatever the firmware writes to
/// the (unimplemented) RCC. Under `-icount shift=0` one guest instruction
/// is one virtual nanosecond, so one tick is 1e9 / 168e6 instructions
/// (cross-checked against mps2-an386's 25 MHz SysTick below).
pub const QEMU_NETDUINO_SYSTICK_HZ: f64 = 168e6;
/// mps2-an386's SysTick: 25 MHz, 40 instructions per tick.
pub const MPS2_INSTRUCTIONS_PER_TICK: f64 = 40.0;
/// How far the two boards' counts of the same snapshot epoch may differ
/// (different builds: the STM32F4's has the HAL, its own capacities and
/// link order), relative.
pub const CROSS_CHECK_TOLERANCE: f64 = 0.10;

/// The LSI's datasheet maximum (STM32F405/407 datasheet, "LSI oscillator
/// characteristics": 17-47 kHz): the IWDG's shortest timeout.
pub const LSI_MAX_HZ: f64 = 47_000.0;
/// The IWDG's divider and reloads, as the firmware programs them
/// (firmware/src/board/stm32f4.rs, `IWDG_TIMEOUT_PLL_MS` and
/// `IWDG_TIMEOUT_HSI_MS` through stm32f4xx-hal 0.23's
/// `IndependentWatchdog::start`, which takes prescaler /256 above 28 ms
/// and reload = ms x 4095 / 32768).
pub const IWDG_PRESCALER: f64 = 256.0;
pub const IWDG_TIMEOUT_PLL_MS: u32 = 5_000;
pub const IWDG_TIMEOUT_HSI_MS: u32 = 15_000;

/// Cycles per instruction, bounded, at 168 MHz with 5 flash wait states
/// behind the ART accelerator: every instruction taken to start a new
/// 128-bit flash line that misses the ART's caches (1 + 5 wait states = 6
/// cycles, RM0090 §3.5.2; a line holds 4 to 8 Thumb-2 instructions), plus
/// 2 cycles of execution on average (Cortex-M4 TRM, table 3-1: most
/// instructions 1 cycle, loads 2, taken branches 2-4, VDIV/VSQRT 14).
pub const CPI_BOUND_PLL: f64 = 8.0;
/// The same at 16 MHz on the HSI: 0 wait states (RM0090 Table 10, HCLK
/// <= 30 MHz), so a fetch is 1 cycle; 1 + 2.
pub const CPI_BOUND_HSI: f64 = 3.0;
/// The link and NMEA UARTs' rate: 115200 baud, 10 bits a byte (8N1).
pub const UART_BYTE_S: f64 = 10.0 / 115_200.0;
/// An NMEA sentence's longest (NMEA 0183: 82 characters with CR LF).
pub const NMEA_SENTENCE_BYTES: usize = 82;

/// The budget in guest instructions of one epoch at `core_hz` with
/// `cpi` cycles per instruction, under an IWDG of `timeout_ms` (nominal):
/// half its shortest timeout, less the blocking transmission of the
/// largest answer and NMEA burst the same byte's handling writes (the
/// watchdog is fed after it).
pub fn budget_instructions(timeout_ms: u32, core_hz: f64, cpi: f64) -> (f64, f64, f64) {
    let reload = (timeout_ms * 4095 / 32768) as f64;
    let t_min_s = (reload + 1.0) * IWDG_PRESCALER / LSI_MAX_HZ;
    let uart_s = uart_seconds();
    let budget = (t_min_s / 2.0 - uart_s) * core_hz / cpi;
    (t_min_s, uart_s, budget)
}

/// The longest blocking transmission one handled byte can cause: the
/// largest response frame and the most NMEA sentences an epoch writes.
pub fn uart_seconds() -> f64 {
    let bytes =
        raim_proto::MAX_RESPONSE_FRAME + raim_proto::nmea::MAX_SENTENCES * NMEA_SENTENCE_BYTES;
    bytes as f64 * UART_BYTE_S
}

pub fn instructions(ticks: u32) -> u64 {
    (f64::from(ticks) * 1e9 / QEMU_NETDUINO_SYSTICK_HZ).round() as u64
}

pub fn netduino() -> QemuSession {
    let elf = raim_qemu::firmware_elf_for(Machine::NetduinoPlus2).unwrap();
    QemuSession::start_with(
        &elf,
        &Options {
            machine: Machine::NetduinoPlus2,
            icount: true,
            ..Options::default()
        },
    )
    .unwrap()
}

/// Sends `command`, waits for its answer, returns the instructions of its
/// epoch and a short description of the answer; an error answer panics.
pub fn epoch(fw: &mut QemuSession, command: CommandRef<'_>) -> (u64, String) {
    let (n, what, error) = epoch_any(fw, command);
    assert!(!error, "{what}");
    (n, what)
}

/// As [`epoch`], an error answer included (`true` in the third place):
/// a refused epoch is counted too.
pub fn epoch_any(fw: &mut QemuSession, command: CommandRef<'_>) -> (u64, String, bool) {
    let seq = fw.send(command).unwrap();
    let r = fw.recv(raim_qemu::ANSWER_TIMEOUT).unwrap();
    assert_eq!(r.seq, Some(seq), "{r:?}");
    let what = match &r.body {
        ResponseBody::Result(w) => format!("{:?}, {} excluded", w.decision, w.exclusions.len()),
        ResponseBody::Araim(a) => match a {
            raim_proto::araim_msg::AraimAnswer::Result(w) => format!(
                "{:?}, {} modes, {:?}{}",
                w.decision,
                w.all_in_view.modes,
                w.fde,
                w.all_in_view
                    .unavailable
                    .map(|u| format!(", {u:?}"))
                    .unwrap_or_default()
            ),
            other => format!("{other:?}"),
        },
        ResponseBody::PfResult(p) => format!("alarm {}, excluded {:?}", p.alarm, p.excluded),
        other => format!("{other:?}"),
    };
    let error = matches!(r.body, ResponseBody::Error(_));
    (
        instructions(fw.status().unwrap().last_epoch_ticks),
        what,
        error,
    )
}
