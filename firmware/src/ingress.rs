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
//!
//! The frames that hold a datagram to the server's port are counted as the stack takes them
//! ([`COUNTERS`]`.arrived`): what of them never reaches the server — the socket was full, or
//! the stack refused the datagram — is counted from that ([`crate::link::StackDrops`]).

use core::task::Context;

use embassy_net::driver::{Capabilities, Driver, HardwareAddress, LinkState, RxToken};
use smoltcp::wire::{EthernetFrame, EthernetProtocol, IpProtocol, Ipv4Packet, UdpPacket};

use crate::link::{COUNTERS, count};
use crate::settings::PORT;

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
        = Counted<D::RxToken<'a>>
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
        let (rx, tx) = self.inner.receive(cx)?;
        self.taken += 1;
        Some((Counted(rx), tx))
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

/// A received frame, counted in [`COUNTERS`]`.arrived` if it holds a datagram to the server's
/// port.
pub struct Counted<T>(T);

impl<T: RxToken> RxToken for Counted<T> {
    fn consume<R, F>(self, f: F) -> R
    where
        F: FnOnce(&mut [u8]) -> R,
    {
        self.0.consume(|frame| {
            if is_datagram_to(frame, PORT) {
                count(&COUNTERS.arrived);
            }
            f(frame)
        })
    }
}

/// Whether `frame` is an Ethernet frame with an IPv4 UDP datagram to `port` (the stack does
/// the remaining checks: addresses, checksums). Only a first fragment has the UDP header.
fn is_datagram_to(frame: &[u8], port: u16) -> bool {
    let Ok(ethernet) = EthernetFrame::new_checked(frame) else {
        return false;
    };
    if ethernet.ethertype() != EthernetProtocol::Ipv4 {
        return false;
    }
    let Ok(ip) = Ipv4Packet::new_checked(ethernet.payload()) else {
        return false;
    };
    ip.next_header() == IpProtocol::Udp
        && ip.frag_offset() == 0
        && UdpPacket::new_checked(ip.payload()).is_ok_and(|udp| udp.dst_port() == port)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frame to 192.168.1.50:7031 from 192.168.1.1:40000 with a 4-byte payload, byte by byte.
    const DATAGRAM: [u8; 46] = [
        // Ethernet: destination, source, type IPv4.
        0x02, 0, 0, 0, 0, 0x50, 0x02, 0, 0, 0, 0, 0x01, 0x08, 0x00, //
        // IPv4: version 4, IHL 5, length 32, no fragment, TTL 64, UDP, checksum, addresses.
        0x45, 0, 0, 32, 0, 0, 0x40, 0, 64, 17, 0xb7, 0x25, 192, 168, 1, 1, 192, 168, 1, 50, //
        // UDP: 40000 -> 7031, length 12, checksum (not checked here), payload.
        0x9c, 0x40, 0x1b, 0x77, 0, 12, 0, 0, b'P', b'S', 0, 0,
    ];

    #[test]
    fn datagrams_to_the_port_are_recognised() {
        assert!(is_datagram_to(&DATAGRAM, 7031));
        assert!(!is_datagram_to(&DATAGRAM, 7032));
        // Another protocol (TCP), a later fragment, an ARP frame, a cut frame: not counted.
        let mut tcp = DATAGRAM;
        tcp[23] = 6;
        assert!(!is_datagram_to(&tcp, 7031));
        let mut fragment = DATAGRAM;
        fragment[21] = 1;
        assert!(!is_datagram_to(&fragment, 7031));
        let mut arp = DATAGRAM;
        arp[12..14].copy_from_slice(&[0x08, 0x06]);
        assert!(!is_datagram_to(&arp, 7031));
        for len in 0..DATAGRAM.len() {
            assert!(!is_datagram_to(&DATAGRAM[..len], 7031), "{len}");
        }
    }
}
