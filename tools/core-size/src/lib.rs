//! A minimal no_std entry point that instantiates `Raim::<32>::process`, so
//! the core's code size on Cortex-M4F can be measured after dead-code
//! elimination (see BENCHMARKS.md for the link command).
#![no_std]


use raim_core::{Config, Epoch, LinearObservation, Raim};

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    loop {}
}

#[no_mangle]
pub extern "C" fn raim_epoch(sats: *const LinearObservation, n: usize, out: *mut f64) {
    let s = unsafe { core::slice::from_raw_parts(sats, n) };
    let mut raim = Raim::<32>::new();
    if let Ok(r) = raim.process(&Config::default(), &Epoch::linear(0.0, s)) {
        unsafe { *out = r.protection.hpl_m };
    }
}
