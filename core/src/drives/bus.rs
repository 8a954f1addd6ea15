//! The CAN controller as the drive manager sees it: non-blocking send and receive.

use armgate_protocol::can::CanFrame;

/// A CAN controller endpoint (embassy style, but without `async`): every call returns at once,
/// so the drive manager can run inside the control loop without ever waiting on the bus.
pub trait CanBus {
    /// Queues `frame` for transmission; frames with lower identifiers go first, equal
    /// identifiers in the order queued.
    fn try_transmit(&mut self, frame: &CanFrame) -> Result<(), TxError>;

    /// The oldest received frame not yet taken, if any.
    fn try_receive(&mut self) -> Option<CanFrame>;

    /// The controller's fault-confinement state.
    fn state(&self) -> BusState;

    /// Brings the bus up to time `now` (s) before the cycle reads it; false if that failed.
    /// Hardware runs by itself (the default); a simulated bus runs its drives here.
    fn advance_to(&mut self, _now: f64) -> bool {
        true
    }

    /// Asks a bus-off controller to rejoin the bus (the client's `ON`): a controller that
    /// latches bus-off clears the latch; one still off goes bus-off again on the next frame.
    /// Controllers that recover by themselves need nothing (the default).
    fn recover(&mut self) {}
}

/// A bus borrowed for good (the firmware keeps its simulated bus in a static).
impl<B: CanBus + ?Sized> CanBus for &mut B {
    fn try_transmit(&mut self, frame: &CanFrame) -> Result<(), TxError> {
        (**self).try_transmit(frame)
    }

    fn try_receive(&mut self) -> Option<CanFrame> {
        (**self).try_receive()
    }

    fn state(&self) -> BusState {
        (**self).state()
    }

    fn advance_to(&mut self, now: f64) -> bool {
        (**self).advance_to(now)
    }

    fn recover(&mut self) {
        (**self).recover();
    }
}

/// The CAN fault-confinement state of the controller (ISO 11898-1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BusState {
    /// Normal operation.
    ErrorActive,
    /// Many errors seen; still sending and receiving.
    ErrorPassive,
    /// Disconnected from the bus after too many transmit errors: nothing is sent or received.
    BusOff,
}

impl BusState {
    /// Error-active, or bus-off: the two states a controller that does not count errors knows.
    pub fn from_bus_off(bus_off: bool) -> Self {
        if bus_off {
            Self::BusOff
        } else {
            Self::ErrorActive
        }
    }
}

/// Why a frame was not queued.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TxError {
    /// The transmit queue is full (the bus is saturated, or nobody acknowledges).
    QueueFull,
    /// The controller is bus-off.
    BusOff,
}
