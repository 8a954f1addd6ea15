//! Paced ingress: the network driver hands the stack at most [`FRAMES_PER_POLL`] received
//! frames per poll of the stack.
//!
//! smoltcp takes every frame the driver has in one poll. Under a flood that is more datagrams
//! than the UDP socket buffers, and the socket drops whatever does not fit — whoever sent it,
//! a stop included — before the UDP server has run once. Paced, the stack yields after a
//! batch (it asks to be polled again at once), the UDP server empties the socket in between,
//! and the socket, sized for two batches ([`crate::net::SOCKET_PACKETS`]), never overflows:
//! what the controller drops under a flood it drops by its own rule, per client
//! ([`crate::link`]), not by arrival order in a full ring.

use core::task::Context;

use embassy_net::driver::{Capabilities, Driver, HardwareAddress, LinkState};

/// Received frames handed to the stack per poll.
pub const FRAMES_PER_POLL: usize = 8;

/// The board's network driver, paced.
pub struct Paced<D> {
    inner: D,
    /// Frames handed over in the current poll.
    taken: usize,
}

impl<D> Paced<D> {
    /// `inner`, paced.
    pub fn new(inner: D) -> Self {
        Self { inner, taken: 0 }
    }
}

impl<D: Driver> Driver for Paced<D> {
    type RxToken<'a>
        = D::RxToken<'a>
    where
        Self: 'a;
    type TxToken<'a>
        = D::TxToken<'a>
    where
        Self: 'a;

    fn receive(&mut self, cx: &mut Context) -> Option<(Self::RxToken<'_>, Self::TxToken<'_>)> {
        if self.taken >= FRAMES_PER_POLL {
            // The rest wait in the driver; the stack runs again after the tasks it woke.
            cx.waker().wake_by_ref();
            return None;
        }
        let frame = self.inner.receive(cx);
        if frame.is_some() {
            self.taken += 1;
        }
        frame
    }

    fn transmit(&mut self, cx: &mut Context) -> Option<Self::TxToken<'_>> {
        self.inner.transmit(cx)
    }

    /// embassy-net asks for the link state once per poll, after the stack's work: a new
    /// batch begins.
    fn link_state(&mut self, cx: &mut Context) -> LinkState {
        self.taken = 0;
        self.inner.link_state(cx)
    }

    fn capabilities(&self) -> Capabilities {
        self.inner.capabilities()
    }

    fn hardware_address(&self) -> HardwareAddress {
        self.inner.hardware_address()
    }
}
