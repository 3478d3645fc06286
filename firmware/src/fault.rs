//! Fail loud and recover: a panic, a hard fault, a stack
//! overflow (`guard`) or a watchdog expiry records its cause (a code and a value: the PC, or the panic's
//! source line) in a RAM record that a reset does not clear (the
//! `.uninit` section of cortex-m-rt, NOLOAD), then resets the unit. At boot
//! the record gives the cause of the last reset and the number of resets
//! since power-on, which every `Status` reports (`Platform::reset_record`).

use core::mem::MaybeUninit;
use core::ptr::{addr_of, addr_of_mut, read_volatile, write_volatile};

use raim_proto::ResetCause;

use crate::board::HardwareReset;

const MAGIC: u32 = 0x5241_494D; // "RAIM"
const CODE_NONE: u32 = 0;
pub const CODE_PANIC: u32 = 1;
pub const CODE_HARD_FAULT: u32 = 2;
pub const CODE_WATCHDOG: u32 = 3;
pub const CODE_STACK_OVERFLOW: u32 = 4;

#[repr(C)]
#[derive(Clone, Copy)]
struct Record {
    magic: u32,
    resets: u32,
    code: u32,
    value: u32,
    check: u32,
}

impl Record {
    fn checksum(&self) -> u32 {
        self.magic
            ^ self.resets.rotate_left(8)
            ^ self.code.rotate_left(16)
            ^ self.value.rotate_left(24)
            ^ 0xA5A5_5A5A
    }
    fn valid(&self) -> bool {
        self.magic == MAGIC && self.check == self.checksum()
    }
    fn sealed(mut self) -> Self {
        self.check = self.checksum();
        self
    }
}

/// Survives a reset (NOLOAD); garbage at power-on, told apart by the magic
/// word and the check word.
#[link_section = ".uninit.raim_fault"]
static mut RECORD: MaybeUninit<Record> = MaybeUninit::uninit();

fn read() -> Record {
    // SAFETY: a plain-old-data record of u32s in RAM owned by this module;
    // any bit pattern is a value (validated by `valid`).
    unsafe { read_volatile(addr_of!(RECORD).cast::<Record>()) }
}

fn write(r: Record) {
    // SAFETY: as for `read`; single core, written only here.
    unsafe { write_volatile(addr_of_mut!(RECORD).cast::<Record>(), r) }
}

/// At boot: the resets since power-on and the last reset's cause; arms
/// the record so that a reset nobody records shows as `Unrecorded`.
///
/// `hw` is what the board's reset-cause register says: a power-on reset
/// starts the count again whatever RAM holds; a watchdog reset that no
/// handler recorded (the STM32F4's IWDG has no early interrupt) is a
/// `Watchdog` reset at an unknown PC (0).
pub fn boot(hw: HardwareReset) -> (u32, ResetCause) {
    let r = read();
    let (resets, cause) = if r.valid() && hw != HardwareReset::PowerOn {
        let cause = match r.code {
            CODE_PANIC => ResetCause::Panic { line: r.value },
            CODE_HARD_FAULT => ResetCause::HardFault { pc: r.value },
            CODE_WATCHDOG => ResetCause::Watchdog { pc: r.value },
            CODE_STACK_OVERFLOW => ResetCause::StackOverflow { address: r.value },
            _ if hw == HardwareReset::Watchdog => ResetCause::Watchdog { pc: 0 },
            _ => ResetCause::Unrecorded,
        };
        (r.resets.wrapping_add(1), cause)
    } else {
        (0, ResetCause::PowerOn)
    };
    write(
        Record {
            magic: MAGIC,
            resets,
            code: CODE_NONE,
            value: 0,
            check: 0,
        }
        .sealed(),
    );
    (resets, cause)
}

/// Record `code` and `value`, then reset the unit.
pub fn record_and_reset(code: u32, value: u32) -> ! {
    cortex_m::interrupt::disable();
    let r = read();
    let resets = if r.valid() { r.resets } else { 0 };
    write(
        Record {
            magic: MAGIC,
            resets,
            code,
            value,
            check: 0,
        }
        .sealed(),
    );
    cortex_m::peripheral::SCB::sys_reset()
}
