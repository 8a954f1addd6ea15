//! FDCAN1 as the drive manager's [`CanBus`]: classic CAN, standard identifiers, at the robot
//! file's `drives.can_bitrate`, on PD0 (RX) / PD1 (TX).
//!
//! embassy's buffered FDCAN driver does the moving: its interrupt (`FDCAN1_IT0`, at
//! [`CAN_PRIORITY`], above the control task) copies frames from the software transmit queue
//! ([`TX_QUEUE`] frames) into the peripheral's 3 TX buffers, and every received frame from the
//! RX FIFOs into the software receive queue ([`RX_QUEUE`] frames). The control task only calls
//! the non-blocking ends of the two queues, so a tick never waits on the bus:
//!
//! * [`CanBus::try_transmit`]: bus-off → [`TxError::BusOff`]; software queue full →
//!   [`TxError::QueueFull`] (the drive manager turns either into `ER35`);
//! * [`CanBus::try_receive`]: the next data frame with a standard identifier; bus-error
//!   reports the driver puts in the same queue, and extended, remote or FD frames, are skipped
//!   and counted ([`CanCounters`]);
//! * [`CanBus::state`]: the peripheral's fault confinement state (`PSR.BO`, `PSR.EP`).
//!
//! The TX buffers run as a FIFO (not as a priority queue): frames go out in the order the drive
//! manager queued them, which keeps a drive's PT point ahead of the query that follows it on
//! the same identifier (a priority queue with equal identifiers sends the lowest buffer first).
//!
//! Bus-off: the automatic recovery of embassy's driver is off, so a bus-off lasts until the
//! drive manager has seen it — [`CanBus::state`] reports it and starts the recovery (the
//! peripheral then waits for 129 × 11 recessive bits, ≈ 2.9 ms at 500 kbit/s, before it sends
//! again). The drive manager latches `ER35 CAN bus off` until the client's `ON`.

use core::sync::atomic::AtomicU32;

use armgate_core::drives::{BusState, CanBus, TxError};
use armgate_protocol::can::CanFrame;
use embassy_stm32::can::enums::BusErrorMode;
use embassy_stm32::can::frame::Frame;
use embassy_stm32::can::{
    BufferedCan, BufferedCanReceiver, BufferedCanSender, CanConfigurator, IT0InterruptHandler,
    IT1InterruptHandler, RxBuf, TxBuf, config::TxBufferMode,
};
use embassy_stm32::interrupt::{InterruptExt, Priority};
use embassy_stm32::peripherals::{FDCAN1, PD0, PD1};
use embassy_stm32::{Peri, bind_interrupts, interrupt};
use embedded_can::Id;
use static_cell::StaticCell;

use crate::link::count;

/// Frames the control task can queue ahead of the peripheral's 3 TX buffers. A cycle sends at
/// most two frames per drive plus the heartbeat (13 for six drives, 17 for eight); the bus
/// carries them within the period, so the queue is empty again by the next tick.
pub const TX_QUEUE: usize = 32;
/// Received frames waiting for the next tick: two answers per drive per cycle plus the
/// drives' heartbeats and emergencies; 64 as the virtual bus's receive FIFO.
pub const RX_QUEUE: usize = 64;
/// Priority of the FDCAN interrupt: above the control task (P6), so that the frames a tick
/// queues reach the TX buffers while the tick still runs; below the time driver and Ethernet.
const CAN_PRIORITY: Priority = Priority::P5;

bind_interrupts!(struct Irqs {
    FDCAN1_IT0 => IT0InterruptHandler<FDCAN1>;
    FDCAN1_IT1 => IT1InterruptHandler<FDCAN1>;
});

static TX_BUF: StaticCell<TxBuf<TX_QUEUE>> = StaticCell::new();
static RX_BUF: StaticCell<RxBuf<RX_QUEUE>> = StaticCell::new();

/// What the adapter skipped, since boot (they wrap after 2^32).
pub struct CanCounters {
    /// Bus errors the controller reported (stuff, form, acknowledge, bit, CRC).
    pub bus_errors: AtomicU32,
    /// Received frames the drive protocol never uses (extended id, remote, FD), skipped.
    pub foreign_frames: AtomicU32,
    /// Bus-off recoveries started.
    pub bus_offs: AtomicU32,
}

/// The counters, read by the status line.
pub static CAN_COUNTERS: CanCounters = CanCounters {
    bus_errors: AtomicU32::new(0),
    foreign_frames: AtomicU32::new(0),
    bus_offs: AtomicU32::new(0),
};

/// FDCAN1, running, as a [`CanBus`].
pub struct Fdcan {
    can: BufferedCan<'static, TX_QUEUE, RX_QUEUE>,
    tx: BufferedCanSender,
    rx: BufferedCanReceiver,
}

impl Fdcan {
    /// Configures FDCAN1 at `bitrate` (125 k, 250 k, 500 k or 1 Mbit/s: the robot file's
    /// choices, all exact from the 120 MHz kernel clock) and joins the bus. Call once.
    pub fn new(
        peri: Peri<'static, FDCAN1>,
        rx: Peri<'static, PD0>,
        tx: Peri<'static, PD1>,
        bitrate: u32,
    ) -> Self {
        let mut configurator = CanConfigurator::new(peri, rx, tx, Irqs);
        configurator.set_bitrate(bitrate);
        let config = configurator
            .config()
            .set_tx_buffer_mode(TxBufferMode::Fifo)
            .set_automatic_bus_off_recovery(false);
        configurator.set_config(config);
        interrupt::FDCAN1_IT0.set_priority(CAN_PRIORITY);
        interrupt::FDCAN1_IT1.set_priority(CAN_PRIORITY);
        let can = configurator
            .into_normal_mode()
            .buffered(TX_BUF.init(TxBuf::new()), RX_BUF.init(RxBuf::new()));
        let tx = can.writer();
        let rx = can.reader();
        Self { can, tx, rx }
    }
}

impl CanBus for Fdcan {
    fn try_transmit(&mut self, frame: &CanFrame) -> Result<(), TxError> {
        if self.state() == BusState::BusOff {
            return Err(TxError::BusOff);
        }
        // A `CanFrame` has an 11-bit identifier and at most 8 bytes: always a valid frame.
        let Ok(frame) = Frame::new_standard(frame.id(), frame.data()) else {
            return Err(TxError::QueueFull);
        };
        self.tx.try_write(frame).map_err(|_| TxError::QueueFull)
    }

    fn try_receive(&mut self) -> Option<CanFrame> {
        // Bounded: the queue holds at most RX_QUEUE entries, each taken once.
        while let Ok(entry) = self.rx.try_receive() {
            let Ok(envelope) = entry else {
                count(&CAN_COUNTERS.bus_errors);
                continue;
            };
            let header = envelope.frame.header();
            let id = match header.id() {
                Id::Standard(id) if !header.rtr() && !header.fdcan() => id.as_raw(),
                _ => {
                    count(&CAN_COUNTERS.foreign_frames);
                    continue;
                }
            };
            match CanFrame::new(id, envelope.frame.data()) {
                Ok(frame) => return Some(frame),
                Err(_) => count(&CAN_COUNTERS.foreign_frames),
            }
        }
        None
    }

    fn state(&self) -> BusState {
        match self.can.properties().bus_error_mode() {
            BusErrorMode::ErrorActive => BusState::ErrorActive,
            BusErrorMode::ErrorPassive => BusState::ErrorPassive,
            BusErrorMode::BusOff => {
                // The peripheral set CCCR.INIT when it went bus-off; clearing it starts the
                // recovery sequence (as embassy's automatic recovery would, but only now that
                // the drive manager has seen the bus-off). PSR.BO stays set until it is done.
                let cccr = embassy_stm32::pac::FDCAN1.cccr();
                if cccr.read().init() {
                    count(&CAN_COUNTERS.bus_offs);
                    cccr.modify(|w| w.set_init(false));
                }
                BusState::BusOff
            }
        }
    }
}
