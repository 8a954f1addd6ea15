//! The send path: replies and notices leave one at a time through their own socket, and a
//! destination that does not resolve costs at most [`RESOLVE_TIMEOUT`], never the receive path.
//!
//! smoltcp keeps a datagram whose destination has not answered ARP at the head of its socket's
//! transmit ring and tries it again every second, for ever: behind it, nothing else is sent,
//! and a server that waits for room in that ring stops reading. So the firmware receives and
//! sends through two sockets, in two loops that never wait on each other (`crate::net`), and
//! the sender hands smoltcp one datagram at a time: if it has not left within
//! [`RESOLVE_TIMEOUT`], the socket is dropped and made anew, the datagram is counted
//! as dropped, and the destination is [`Unreachable`] for [`UNREACHABLE_FOR`]: its datagrams
//! are dropped (counted) without waiting, and after that one is tried again.

use core::net::{IpAddr, SocketAddr};
use embassy_net::udp::{PacketMetadata, UdpSocket};

use embassy_net::Stack;
use embassy_time::{Duration, Instant, with_timeout};

use crate::link::{COUNTERS, OUTGOING, count};
use crate::net::PACKET_BYTES;
use crate::settings::PORT;

/// How long a datagram may wait for its destination's link-layer address. A client on the
/// board's network answers ARP within a millisecond; one that has left never does.
pub const RESOLVE_TIMEOUT: Duration = Duration::from_millis(100);
/// How long a destination that did not resolve has its datagrams dropped without trying
/// (smoltcp's own interval between two ARP requests for one address).
pub const UNREACHABLE_FOR: Duration = Duration::from_secs(1);
/// Destinations remembered as unreachable at once; a new one replaces the oldest.
const UNREACHABLE_ENTRIES: usize = 8;

/// Destinations that did not resolve lately.
#[derive(Default)]
pub struct Unreachable {
    /// Each with the time it was found unreachable.
    entries: [Option<(IpAddr, Instant)>; UNREACHABLE_ENTRIES],
}

impl Unreachable {
    /// True if `address` did not resolve within [`UNREACHABLE_FOR`] before `now`.
    pub fn holds(&self, address: IpAddr, now: Instant) -> bool {
        self.entries.iter().flatten().any(|(a, since)| {
            *a == address && now.saturating_duration_since(*since) < UNREACHABLE_FOR
        })
    }

    /// Remembers that `address` did not resolve at `now`, in its own entry, a free or expired
    /// one, or the oldest.
    pub fn mark(&mut self, address: IpAddr, now: Instant) {
        let age = |e: &Option<(IpAddr, Instant)>| match e {
            Some((a, _)) if *a == address => Duration::MAX,
            Some((_, since)) => now.saturating_duration_since(*since),
            None => Duration::MAX,
        };
        if let Some(entry) = self.entries.iter_mut().max_by_key(|e| age(e)) {
            *entry = Some((address, now));
        }
    }
}

/// The sending socket's buffers: one datagram out; in, nothing it would ever get (the
/// receiving socket, first on the port, takes every datagram).
pub struct Buffers {
    tx_meta: [PacketMetadata; 1],
    tx: [u8; PACKET_BYTES],
    rx_meta: [PacketMetadata; 1],
    rx: [u8; PACKET_BYTES],
}

impl Buffers {
    /// Empty buffers.
    pub const fn new() -> Self {
        Self {
            tx_meta: [PacketMetadata::EMPTY; 1],
            tx: [0; PACKET_BYTES],
            rx_meta: [PacketMetadata::EMPTY; 1],
            rx: [0; PACKET_BYTES],
        }
    }
}

/// Sends what the control task queued in [`OUTGOING`], for ever, through a socket of its own
/// on the server's port (to be made after the receiving socket). When a datagram does not leave
/// in time, the socket is dropped and made anew: closing it would empty its ring but not
/// smoltcp's note to wait a second for that neighbour before it sends anything else.
pub async fn run(stack: Stack<'static>, buffers: &mut Buffers) {
    let mut unreachable = Unreachable::default();
    loop {
        let mut socket = UdpSocket::new(
            stack,
            &mut buffers.rx_meta,
            &mut buffers.rx,
            &mut buffers.tx_meta,
            &mut buffers.tx,
        );
        if let Err(e) = socket.bind(PORT) {
            defmt::error!(
                "net: cannot bind the sending socket to port {}: {}",
                PORT,
                e
            );
            return;
        }
        send_until_stuck(&mut socket, &mut unreachable).await;
    }
}

/// Sends through `socket` until a datagram does not leave within [`RESOLVE_TIMEOUT`] (its
/// destination is then marked unreachable, the datagram counted as dropped).
async fn send_until_stuck(socket: &mut UdpSocket<'_>, unreachable: &mut Unreachable) {
    loop {
        let outgoing = OUTGOING.receive().await;
        let peer = outgoing.peer;
        if unreachable.holds(peer.ip(), Instant::now()) {
            count(&COUNTERS.unreachable);
            continue;
        }
        // The stack speaks IPv4 only (so every request came from an IPv4 address). The ring is
        // empty: sending only copies the datagram.
        let SocketAddr::V4(to) = peer else {
            count(&COUNTERS.send_errors);
            continue;
        };
        if socket.send_to(outgoing.payload(), to).await.is_err() {
            count(&COUNTERS.send_errors);
            continue;
        }
        if with_timeout(RESOLVE_TIMEOUT, socket.flush()).await.is_err() {
            count(&COUNTERS.unreachable);
            unreachable.mark(peer.ip(), Instant::now());
            return;
        }
    }
}
