//! The send path: replies and notices leave one at a time through sockets of their own, and a
//! destination that does not resolve costs at most [`RESOLVE_TIMEOUT`], never the receive path
//! nor the clients whose address is known.
//!
//! smoltcp keeps a datagram whose destination has not answered ARP at the head of its socket's
//! transmit ring and tries it again every second, for ever: behind it, nothing else is sent,
//! and a server that waits for room in that ring stops reading. So the firmware receives and
//! sends through separate sockets, in loops that never wait on each other (`crate::net`), and
//! each sending socket gets one datagram at a time: if it has not left within
//! [`RESOLVE_TIMEOUT`], the socket is dropped and made anew, the datagram is counted as
//! dropped, and the destination is unreachable for [`UNREACHABLE_FOR`]: its datagrams are
//! dropped (counted) without waiting, and after that one is tried again.
//!
//! A datagram to a destination that resolved lately ([`RESOLVED_FOR`]) leaves through one
//! socket at once; one to any other destination waits for its neighbour through another
//! ([`PROBES`] of them at most, the rest dropped and counted; a reply to a stop waits apart
//! and goes first). Replies to a flood from many forged addresses, each costing its wait, so
//! delay only each other, not the clients that were answered before, nor a stop's reply
//! for long (docs/safety.md).

use core::cell::RefCell;
use core::net::{IpAddr, SocketAddr};
use embassy_net::udp::{PacketMetadata, UdpSocket};

use embassy_futures::join::join;
use embassy_futures::select::{Either, select};
use embassy_net::Stack;
use embassy_sync::blocking_mutex::raw::NoopRawMutex;
use embassy_sync::channel::Channel;
use embassy_time::{Duration, Instant, with_timeout};

use armgate_core::cycle::answers_a_stop;

use crate::link::{COUNTERS, Datagram, OUTGOING, count};
use crate::net::PACKET_BYTES;
use crate::settings::PORT;

/// How long a datagram may wait for its destination's link-layer address. A client on the
/// board's network answers ARP within a millisecond; one that has left never does.
pub const RESOLVE_TIMEOUT: Duration = Duration::from_millis(100);
/// How long a stop's reply may wait for its destination's link-layer address: smoltcp sends
/// one ARP request a second at most, whatever the address, so a new client's may have to wait
/// for the next.
pub const STOP_RESOLVE_TIMEOUT: Duration = Duration::from_millis(1_100);
/// How long a destination that did not resolve has its datagrams dropped without trying
/// (smoltcp's own interval between two ARP requests for one address).
pub const UNREACHABLE_FOR: Duration = Duration::from_secs(1);
/// How long a destination whose datagram left counts as resolved (smoltcp keeps a neighbour
/// for a minute).
pub const RESOLVED_FOR: Duration = Duration::from_secs(30);
/// Destinations remembered at once, in each table; a new one replaces the oldest.
const ENTRIES: usize = 8;
/// Datagrams to destinations not known to resolve that may wait for their turn.
const PROBES: usize = 2;

/// Destinations and when each was last seen to resolve, or not to.
#[derive(Default)]
pub struct Recent {
    /// Each with the time it was noted.
    entries: [Option<(IpAddr, Instant)>; ENTRIES],
}

impl Recent {
    /// True if `address` was noted less than `lifetime` before `now`.
    pub fn holds(&self, address: IpAddr, now: Instant, lifetime: Duration) -> bool {
        self.entries
            .iter()
            .flatten()
            .any(|(a, since)| *a == address && now.saturating_duration_since(*since) < lifetime)
    }

    /// Notes `address` at `now`, in its own entry, a free one, or the oldest.
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

    /// Forgets `address`.
    pub fn forget(&mut self, address: IpAddr) {
        for entry in &mut self.entries {
            if entry.is_some_and(|(a, _)| a == address) {
                *entry = None;
            }
        }
    }
}

/// What the sending loops know of the destinations.
#[derive(Default)]
struct Neighbours {
    resolved: Recent,
    unreachable: Recent,
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

/// Two queues of a sending socket, the first served first.
type Queues<'a, const M: usize, const N: usize> = (
    &'a Channel<NoopRawMutex, Datagram, M>,
    &'a Channel<NoopRawMutex, Datagram, N>,
);

/// Sends what the control task queued in [`OUTGOING`], for ever, through two sockets of its
/// own on the server's port (to be made after the receiving socket): one for destinations that
/// resolved lately, one that waits for the others' neighbours.
pub async fn run(stack: Stack<'static>, known: &mut Buffers, probing: &mut Buffers) {
    let neighbours = RefCell::new(Neighbours::default());
    let known_queue = Channel::<NoopRawMutex, Datagram, PROBES>::new();
    let probes = Channel::<NoopRawMutex, Datagram, PROBES>::new();
    let stop_probes = Channel::<NoopRawMutex, Datagram, PROBES>::new();
    let sort = async {
        loop {
            let outgoing = OUTGOING.receive().await;
            let (ip, now) = (outgoing.peer.ip(), Instant::now());
            let (unreachable, resolved) = {
                let n = neighbours.borrow();
                (
                    n.unreachable.holds(ip, now, UNREACHABLE_FOR),
                    n.resolved.holds(ip, now, RESOLVED_FOR),
                )
            };
            if unreachable {
                count(&COUNTERS.unreachable);
            } else if resolved {
                known_queue.send(outgoing).await;
            } else if answers_a_stop(outgoing.payload()) {
                if stop_probes.try_send(outgoing).is_err() {
                    count(&COUNTERS.unreachable);
                }
            } else if probes.try_send(outgoing).is_err() {
                count(&COUNTERS.unreachable);
            }
        }
    };
    join(
        sort,
        join(
            send_through(stack, known, (&known_queue, &known_queue), &neighbours),
            send_through(stack, probing, (&stop_probes, &probes), &neighbours),
        ),
    )
    .await;
}

/// Sends what the queues hold (the first before the second) through a socket on `buffers`,
/// made anew whenever a datagram does not leave in time.
async fn send_through<const M: usize, const N: usize>(
    stack: Stack<'static>,
    buffers: &mut Buffers,
    queues: Queues<'_, M, N>,
    neighbours: &RefCell<Neighbours>,
) {
    loop {
        let mut socket = UdpSocket::new(
            stack,
            &mut buffers.rx_meta,
            &mut buffers.rx,
            &mut buffers.tx_meta,
            &mut buffers.tx,
        );
        if let Err(e) = socket.bind(PORT) {
            defmt::error!("net: cannot bind a sending socket to port {}: {}", PORT, e);
            return;
        }
        send_until_stuck(&mut socket, queues, neighbours).await;
    }
}

/// Sends through `socket` until a datagram does not leave within [`RESOLVE_TIMEOUT`] (a stop's
/// reply: [`STOP_RESOLVE_TIMEOUT`]; its
/// destination is then marked unreachable, the datagram counted as dropped); a destination
/// whose datagram left is marked resolved.
async fn send_until_stuck<const M: usize, const N: usize>(
    socket: &mut UdpSocket<'_>,
    (first, second): Queues<'_, M, N>,
    neighbours: &RefCell<Neighbours>,
) {
    loop {
        let (Either::First(outgoing) | Either::Second(outgoing)) =
            select(first.receive(), second.receive()).await;
        let peer = outgoing.peer;
        if neighbours
            .borrow()
            .unreachable
            .holds(peer.ip(), Instant::now(), UNREACHABLE_FOR)
        {
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
        let wait = if answers_a_stop(outgoing.payload()) {
            STOP_RESOLVE_TIMEOUT
        } else {
            RESOLVE_TIMEOUT
        };
        let left = with_timeout(wait, socket.flush()).await.is_ok();
        let mut n = neighbours.borrow_mut();
        if left {
            n.resolved.mark(peer.ip(), Instant::now());
        } else {
            count(&COUNTERS.unreachable);
            n.resolved.forget(peer.ip());
            n.unreachable.mark(peer.ip(), Instant::now());
            return;
        }
    }
}
