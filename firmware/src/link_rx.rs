//! No byte lost: the link UART's receive interrupt moves bytes into a
//! 4 KiB ring (`heapless::spsc::Queue`), and the main loop takes them out
//! and runs the protocol on them. While an epoch is computed or an answer
//! is sent, the bytes that arrive wait in the ring instead of overrunning
//! the UART.
//!
//! The ring and the UART's receive port sit in critical-section
//! mutexes, and both sides take them inside a critical section (the main loop for one byte at a time: a few cycles with
//! interrupts masked). The ring is the owned `Queue<u8, RING_SLOTS>`,
//! whose index arithmetic is on the constant `RING_SLOTS`: its split
//! halves carry the capacity at run time, and their `% capacity` is a
//! division-by-zero check the build keeps. The `RefCell` is borrowed with
//! `try_borrow_mut`, never `borrow_mut`: every borrow is inside a critical
//! section and none calls back into this module, so it cannot fail, and
//! the firmware links no panic path here (docs/EVIDENCE.md "Panic
//! sites").
//!
//! When the ring is full the interrupt stops reading: the byte stays in the
//! UART, the RX interrupt is disabled and the event is counted
//! (`rx_ring_overflows`); the main loop resumes reception when it has made
//! room (`pump`). On a board without flow control a further byte then
//! overruns the UART, which the UART flags and `pump` counts
//! (`uart_overruns`); the frame it belonged to is answered as a bad frame.
//! Under QEMU the UART model holds the sender back instead, so nothing is
//! lost. Both counters are in every `Status`.
//!
//! The interrupt reaches `on_irq` through cortex-m-rt's `DefaultHandler`,
//! which receives the IRQ number (`main.rs`): no device crate and no
//! hand-written vector table. The port is the active board's
//! ([`crate::board::Board::LinkRx`]).

use core::cell::RefCell;
use core::sync::atomic::{AtomicU32, Ordering};

use cortex_m::interrupt::{CriticalSection, Mutex};
use heapless::spsc::Queue;

use crate::board::{LinkRxPort, RxPort};

/// Ring size; it holds `RING_SLOTS - 1` bytes: 4 KiB, the bytes of 355 ms
/// at 115200 baud, above the longest epoch at the real board's 16 MHz
/// (BENCHMARKS.md) plus the largest answer's transmission time.
pub const RING_SLOTS: usize = 4096;

static OVERRUNS: AtomicU32 = AtomicU32::new(0);
static RING_FULL: AtomicU32 = AtomicU32::new(0);

/// The ring and the reception state, all zero at reset (`.bss`).
struct Ring {
    queue: Queue<u8, RING_SLOTS>,
    /// Reception paused on a full ring (RX interrupt disabled).
    paused: bool,
}

/// Initialised by a `const` value, like every large static
/// (`statics.rs`): the 4 KiB ring is never built on the stack, and, all
/// zero, it is in `.bss` (the port's `None` is not all zero on every
/// board, so it has a static of its own). The STM32F4's build with the
/// stream has it in the core-coupled memory (`.ccmram`, zero-filled by
/// `main` before the receive interrupt is enabled, `statics::zero_ccm`;
/// the ring is written by the interrupt handler, not by DMA, which CCM
/// would not take), leaving its SRAM to the stream receiver
/// (docs/FLASH.md).
#[cfg_attr(
    all(feature = "board-stm32f4", feature = "rtcm"),
    link_section = ".ccmram.raim_ring"
)]
static RING: Mutex<RefCell<Ring>> = Mutex::new(RefCell::new(Ring {
    queue: Queue::new(),
    paused: false,
}));

/// The UART's receive port, set by [`init`].
static PORT: Mutex<RefCell<Option<RxPort>>> = Mutex::new(RefCell::new(None));

/// The main loop's handle on the ring: takes bytes in arrival order. Only
/// [`init`] makes one.
pub struct LinkRx {
    _once: (),
}

/// Set up the ring; call once, with interrupts masked, before they are
/// enabled. `None` if called twice.
pub fn init(port: RxPort) -> Option<LinkRx> {
    cortex_m::interrupt::free(|cs| {
        let mut slot = PORT.borrow(cs).try_borrow_mut().ok()?;
        if slot.is_some() {
            return None;
        }
        *slot = Some(port);
        Some(LinkRx { _once: () })
    })
}

/// Runs `f` on the port and the ring, borrowed inside the critical section
/// `cs`; `None` before [`init`] or were either found borrowed (which the
/// critical section rules out: no borrow calls back into this module).
fn with_rx<R>(cs: &CriticalSection, f: impl FnOnce(&mut RxPort, &mut Ring) -> R) -> Option<R> {
    let mut port = PORT.borrow(cs).try_borrow_mut().ok()?;
    let mut ring = RING.borrow(cs).try_borrow_mut().ok()?;
    Some(f(port.as_mut()?, &mut ring))
}

/// Move the UART's waiting bytes into the ring; on a full ring, pause.
fn pump_into(port: &mut RxPort, ring: &mut Ring) {
    while port.rx_ready() {
        if ring.queue.is_full() {
            if !ring.paused {
                RING_FULL.fetch_add(1, Ordering::Relaxed);
                ring.paused = true;
                port.set_irq(false);
            }
            return;
        }
        let (byte, lost) = port.read();
        if lost {
            OVERRUNS.fetch_add(1, Ordering::Relaxed);
        }
        if let Some(b) = byte {
            // `is_full()` said there is room, inside this critical section.
            let _ = ring.queue.enqueue(b);
        }
    }
    if ring.paused {
        ring.paused = false;
        port.set_irq(true);
    }
}

/// The link UART's receive interrupt. (Were the port or the ring ever
/// found borrowed, which a critical section rules out, the interrupt would
/// stay pending, the main loop would stop feeding the watchdog and the
/// unit would reset: fail loud, not a wrong answer.)
pub fn on_irq() {
    cortex_m::interrupt::free(|cs| {
        with_rx(cs, |port, ring| {
            port.ack();
            pump_into(port, ring);
        })
    });
}

impl LinkRx {
    /// The next received byte, if any.
    pub fn next(&mut self) -> Option<u8> {
        cortex_m::interrupt::free(|cs| RING.borrow(cs).try_borrow_mut().ok()?.queue.dequeue())
    }

    /// Called by the main loop with interrupts masked when the ring is
    /// empty: resumes a paused reception (the UART's interrupt will not
    /// fire again for the byte it holds) and reports whether a byte is now
    /// waiting, so the loop does not sleep on it.
    pub fn pump(&mut self, cs: &CriticalSection) -> bool {
        with_rx(cs, |port, ring| {
            pump_into(port, ring);
            !ring.queue.is_empty()
        })
        // Not reachable (see `with_rx`). A waiting byte is assumed: the
        // loop neither sleeps nor feeds the watchdog, which resets the
        // unit (fail loud).
        .unwrap_or(true)
    }
}

/// (UART overruns, ring-full events) since reset.
pub fn counters() -> (u32, u32) {
    (
        OVERRUNS.load(Ordering::Relaxed),
        RING_FULL.load(Ordering::Relaxed),
    )
}
