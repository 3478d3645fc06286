//! The stack guard: an MPU region with no access between the
//! statics and the stack, so that an overflow faults instead of running
//! the stack down into the static server state (configuration, MCUSUM
//! state, threshold cache). Both boards (Cortex-M4 PMSAv7 MPU).
//!
//! The stack grows down from the top of RAM; the statics end at `__sheap`
//! (the fault record, `.uninit`, is the last of them). The guard is the
//! 1 KiB at `__sheap` rounded up to 1 KiB. A push into it is an MPU
//! violation; MemManage is left disabled, so it escalates to HardFault,
//! where the MPU is off (MPU_CTRL.HFNMIENA = 0): the HardFault frame
//! (up to 104 bytes with the FP context) and the handler's few words land
//! in the guard, not in the statics. The handler sees its frame inside
//! the guard ([`hit`]), records `StackOverflow { address: frame }` and
//! resets (`fault`), without logging (which could run deeper).

use core::ptr::addr_of;

use cortex_m::peripheral::MPU;

/// Size of the guard region, bytes: room for the HardFault entry and its
/// handler, which run inside it.
pub const GUARD_BYTES: usize = 1024;

extern "C" {
    /// End of statically allocated RAM (cortex-m-rt).
    static __sheap: u32;
}

/// First byte of the guard region.
pub fn base() -> usize {
    (addr_of!(__sheap) as usize + GUARD_BYTES - 1) & !(GUARD_BYTES - 1)
}

/// First byte above the guard: the lowest address the stack may use.
pub fn end() -> usize {
    base() + GUARD_BYTES
}

const CTRL_ENABLE: u32 = 1 << 0;
const CTRL_PRIVDEFENA: u32 = 1 << 2;
const RASR_XN: u32 = 1 << 28;
/// SIZE field: region of 2^(9 + 1) = 1024 bytes; AP = 000, no access.
const RASR_SIZE_1K: u32 = 9 << 1;
const RASR_ENABLE: u32 = 1 << 0;

/// Program MPU region 0 as the guard and enable the MPU (the default map
/// stays for everything else, PRIVDEFENA). The MPU is the core's
/// (`cortex_m::Peripherals`), owned by `main` and lent here once.
pub fn enable(mpu: &mut MPU) {
    // SAFETY: the architecture's MPU registers (ARMv7-M B3.5); region 0
    // covers 1 KiB between the statics and the stack that nothing uses.
    unsafe {
        mpu.rnr.write(0);
        mpu.rbar.write(base() as u32);
        mpu.rasr.write(RASR_XN | RASR_SIZE_1K | RASR_ENABLE);
        mpu.ctrl.write(CTRL_ENABLE | CTRL_PRIVDEFENA);
    }
    cortex_m::asm::dsb();
    cortex_m::asm::isb();
}

/// Whether a hard fault whose exception frame is at `frame_addr` came
/// from the stack reaching the guard: the frame was stacked in or below it.
pub fn hit(frame_addr: usize) -> bool {
    frame_addr < end()
}

/// Test hook: recurse until the guard stops it.
#[cfg(feature = "board-qemu")]
#[inline(never)]
pub fn overflow(depth: u32) -> u32 {
    let frame = [depth; 64];
    let frame = core::hint::black_box(frame);
    if depth == u32::MAX {
        return 0;
    }
    overflow(depth + 1).wrapping_add(frame.iter().fold(0, |a, b| a ^ b))
}
