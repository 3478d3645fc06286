//! No byte lost: the link UART's receive interrupt moves bytes
//! into a lock-free single-producer single-consumer ring
//! (`heapless::spsc`), and the main loop takes them out and runs the
//! protocol on them. While an epoch is computed or an answer is sent, the
//! bytes that arrive wait in the ring instead of overrunning the UART.
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
use heapless::spsc::{Consumer, Producer, Queue};

use crate::board::{LinkRxPort, RxPort};
use crate::statics::ConstStaticCell;

/// Ring size; it holds `RING_SLOTS - 1` bytes: 4 KiB, the bytes of 355 ms
/// at 115200 baud, above the longest epoch at the real board's 16 MHz
/// (BENCHMARKS.md) plus the largest answer's transmission time.
pub const RING_SLOTS: usize = 4096;

static OVERRUNS: AtomicU32 = AtomicU32::new(0);
static RING_FULL: AtomicU32 = AtomicU32::new(0);

/// The interrupt's side: the UART's receive port and the ring's producer.
struct Rx {
    port: RxPort,
    producer: Producer<'static, u8>,
    /// Reception paused on a full ring (RX interrupt disabled).
    paused: bool,
}

static RX: Mutex<RefCell<Option<Rx>>> = Mutex::new(RefCell::new(None));

/// The main loop's side: takes bytes in arrival order.
pub struct LinkRx {
    consumer: Consumer<'static, u8>,
}

/// Set up the ring; call once, with interrupts masked, before they are
/// enabled. `None` if called twice.
pub fn init(port: RxPort) -> Option<LinkRx> {
    // The 4 KiB ring in the firmware's static pattern (`statics.rs`).
    static QUEUE: ConstStaticCell<Queue<u8, RING_SLOTS>> = ConstStaticCell::new(Queue::new());
    let queue = QUEUE.try_take()?;
    let (producer, consumer) = queue.split();
    cortex_m::interrupt::free(|cs| {
        RX.borrow(cs).replace(Some(Rx {
            port,
            producer,
            paused: false,
        }))
    });
    Some(LinkRx { consumer })
}

/// Move the UART's waiting bytes into the ring; on a full ring, pause.
fn pump_into(rx: &mut Rx) {
    while rx.port.rx_ready() {
        if !rx.producer.ready() {
            if !rx.paused {
                RING_FULL.fetch_add(1, Ordering::Relaxed);
                rx.paused = true;
                rx.port.set_irq(false);
            }
            return;
        }
        let (byte, lost) = rx.port.read();
        if lost {
            OVERRUNS.fetch_add(1, Ordering::Relaxed);
        }
        if let Some(b) = byte {
            // `ready()` said there is room, and only this side enqueues.
            let _ = rx.producer.enqueue(b);
        }
    }
    if rx.paused {
        rx.paused = false;
        rx.port.set_irq(true);
    }
}

/// The link UART's receive interrupt.
pub fn on_irq() {
    cortex_m::interrupt::free(|cs| {
        if let Some(rx) = RX.borrow(cs).borrow_mut().as_mut() {
            rx.port.ack();
            pump_into(rx);
        }
    });
}

impl LinkRx {
    /// The next received byte, if any.
    pub fn next(&mut self) -> Option<u8> {
        self.consumer.dequeue()
    }

    /// Called by the main loop with interrupts masked when the ring is
    /// empty: resumes a paused reception (the UART's interrupt will not
    /// fire again for the byte it holds) and reports whether a byte is now
    /// waiting, so the loop does not sleep on it.
    pub fn pump(&mut self, cs: &CriticalSection) -> bool {
        if let Some(rx) = RX.borrow(cs).borrow_mut().as_mut() {
            pump_into(rx);
        }
        self.consumer.ready()
    }
}

/// (UART overruns, ring-full events) since reset.
pub fn counters() -> (u32, u32) {
    (
        OVERRUNS.load(Ordering::Relaxed),
        RING_FULL.load(Ordering::Relaxed),
    )
}
