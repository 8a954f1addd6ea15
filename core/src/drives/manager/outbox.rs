//! The drive manager's frames sent in one cycle.

use armgate_protocol::can::{CanFrame, NodeMessage};

use crate::drives::bus::{CanBus, TxError};
use crate::drives::drive::Drive;
use crate::drives::startup::Outgoing;

/// This cycle's sending: frames go to the bus, requests are counted on their drive's link,
/// and the first failure is kept.
pub(super) struct Outbox<'a, B: CanBus> {
    pub bus: &'a mut B,
    pub cycle: u32,
    pub error: Option<TxError>,
}

impl<B: CanBus> Outbox<'_, B> {
    /// Sends `frame`; false if the bus refused it.
    pub fn send(&mut self, frame: &CanFrame) -> bool {
        match self.bus.try_transmit(frame) {
            Ok(()) => true,
            Err(error) => {
                self.error.get_or_insert(error);
                false
            }
        }
    }

    /// Sends a request to `drive`, which now owes an answer.
    pub fn request(&mut self, drive: &mut Drive, frame: &Outgoing) {
        let frame = match *frame {
            Outgoing::Interpreter(request) => request.to_frame(drive.node),
            Outgoing::Sdo(request) => request.to_frame(drive.node),
        };
        if self.send(&frame) {
            drive.link.sent(self.cycle);
        }
    }
}
