//! What passes between the UDP server (thread executor) and the control task (interrupt
//! executor): two bounded queues of datagrams, and counters of what had to be dropped.
//!
//! The control task owns the core ([`CommandHandler`] and the drives); the UDP server never
//! touches it. Requests wait in [`REQUESTS`] until the next tick handles them all; replies and
//! unsolicited notices wait in [`OUTGOING`] until the UDP server sends them. Neither side ever
//! waits on the other: a full queue drops the datagram and counts it ([`COUNTERS`]).
//!
//! One source address may hold at most half of the waiting requests ([`offer`],
//! [`take`]): a client that floods the controller fills its own share, and the others' requests
//! — a stop among them — still find room and are handled in the next tick. A flood from more
//! addresses than the queue has places fills it all the same, so stops and the holder's
//! requests ([`goes_ahead`]) wait in a queue of their own ([`AHEAD`]), served first.
//!
//! [`CommandHandler`]: armgate_core::command::CommandHandler

use core::cell::{Cell, RefCell};
use core::net::{IpAddr, SocketAddr};
use core::sync::atomic::{AtomicU32, Ordering};

use armgate_core::command::NOTICE_CAPACITY;
use armgate_core::cycle::REQUESTS_PER_TICK;
use armgate_core::cycle::{Shares, goes_ahead};
use embassy_sync::blocking_mutex::Mutex;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::channel::Channel;

/// Requests that can wait for the next tick. A client waits for each reply (the `armgate`
/// client resends after 200 ms), so one client has at most one request in flight; 8 leave room
/// for a few clients and for bursts. The socket buffers another [`crate::net::SOCKET_PACKETS`]
/// datagrams before the queue.
pub const REQUEST_QUEUE: usize = REQUESTS_PER_TICK;
/// Stops and the holder's requests that can wait for the next tick: a few, one source at most
/// half of them (a client waits for each reply).
pub const AHEAD_QUEUE: usize = 4;
/// Replies and notices waiting to be sent: one tick produces at most one reply per queued
/// request and at most the notices the core's relay holds; the UDP server empties the queue
/// between two ticks, except while a destination fails to resolve
/// ([`crate::sender::RESOLVE_TIMEOUT`]): room for four ticks of that.
pub const OUTGOING_QUEUE: usize = 4 * (REQUEST_QUEUE + NOTICE_CAPACITY);

/// A datagram of the client protocol and the peer it came from or goes to.
pub type Datagram = armgate_core::cycle::Datagram<SocketAddr>;

/// Requests from allowed sources, in arrival order ([`offer`], [`take`]).
static REQUESTS: Channel<CriticalSectionRawMutex, Datagram, REQUEST_QUEUE> = Channel::new();
/// Stops and the holder's requests, in arrival order, served before [`REQUESTS`].
static AHEAD: Channel<CriticalSectionRawMutex, Datagram, AHEAD_QUEUE> = Channel::new();
/// Replies and notices, in the order the control task produced them.
pub static OUTGOING: Channel<CriticalSectionRawMutex, Datagram, OUTGOING_QUEUE> = Channel::new();

/// Event counters since boot (they wrap after 2^32).
pub struct Counters {
    /// Frames with a datagram to the UDP port that the network driver handed the stack
    /// ([`crate::ingress`]).
    pub arrived: AtomicU32,
    /// Of those, the ones the stack dropped before the UDP server took them: its socket was
    /// full, or it refused the datagram (a bad checksum, another destination address).
    /// Updated whenever the server has emptied the socket ([`StackDrops`]).
    pub stack_dropped: AtomicU32,
    /// Requests passed to the control task.
    pub received: AtomicU32,
    /// Datagrams from sources not on the allow-list (dropped).
    pub foreign: AtomicU32,
    /// Requests dropped because [`REQUESTS`] was full.
    pub requests_full: AtomicU32,
    /// Replies and notices dropped because [`OUTGOING`] was full.
    pub outgoing_full: AtomicU32,
    /// Datagrams the network stack refused to send (no route, not bound).
    pub send_errors: AtomicU32,
    /// Replies and notices dropped because their destination did not resolve (no answer to
    /// ARP: a client gone, a forged source).
    pub unreachable: AtomicU32,
}

impl Counters {
    const fn new() -> Self {
        Self {
            arrived: AtomicU32::new(0),
            stack_dropped: AtomicU32::new(0),
            received: AtomicU32::new(0),
            foreign: AtomicU32::new(0),
            requests_full: AtomicU32::new(0),
            outgoing_full: AtomicU32::new(0),
            send_errors: AtomicU32::new(0),
            unreachable: AtomicU32::new(0),
        }
    }
}

/// The counters, shared by every task.
pub static COUNTERS: Counters = Counters::new();

/// Adds one to `counter`.
pub fn count(counter: &AtomicU32) {
    counter.fetch_add(1, Ordering::Relaxed);
}

/// The current value of `counter`.
pub fn read(counter: &AtomicU32) -> u32 {
    counter.load(Ordering::Relaxed)
}

/// The UDP server's count of the datagrams it took from its socket, and from it the stack's
/// drops: of the datagrams that arrived for the port, those not taken once the socket is empty
/// (the driver counts an arrival in the same executor, before the stack handles the frame, so
/// with the socket empty every arrival so far was either taken or dropped).
#[derive(Default)]
pub struct StackDrops {
    /// Datagrams taken from the socket since boot (wrapping, as the counters).
    taken: u32,
}

impl StackDrops {
    /// One datagram taken; with `socket_empty`, [`COUNTERS`]`.stack_dropped` is brought up to
    /// date.
    pub fn taken(&mut self, socket_empty: bool) {
        self.taken = self.taken.wrapping_add(1);
        if socket_empty {
            let arrived = read(&COUNTERS.arrived);
            COUNTERS
                .stack_dropped
                .store(arrived.wrapping_sub(self.taken), Ordering::Relaxed);
        }
    }
}

/// How many of the waiting requests each source holds, in each queue.
struct Lanes {
    requests: Shares<REQUEST_QUEUE>,
    ahead: Shares<AHEAD_QUEUE>,
}

static LANES: Mutex<CriticalSectionRawMutex, RefCell<Lanes>> = Mutex::new(RefCell::new(Lanes {
    requests: Shares::new(),
    ahead: Shares::new(),
}));

/// The address of the client that holds the arm, as of the last tick (control task side).
static HOLDER: Mutex<CriticalSectionRawMutex, Cell<Option<IpAddr>>> = Mutex::new(Cell::new(None));

/// Sets the address of the client that holds the arm (control task side, after each tick).
pub fn set_holder(holder: Option<IpAddr>) {
    HOLDER.lock(|h| h.set(holder));
}

/// Queues `request` for the control task (UDP server side); false if the queue is full or its
/// source already holds its share (the datagram is dropped). A request that goes ahead does,
/// unless its source still has requests in the other queue (a source's requests keep their
/// order) or the ahead queue has no room for it.
pub fn offer(request: Datagram) -> bool {
    let source = request.peer.ip();
    let holder = HOLDER.lock(Cell::get);
    LANES.lock(|lanes| {
        let lanes = &mut *lanes.borrow_mut();
        let ahead = goes_ahead(request.payload(), source, holder)
            && lanes.requests.held(source) == 0
            && lanes
                .ahead
                .admit(source, || AHEAD.try_send(request).is_ok());
        ahead
            || lanes
                .requests
                .admit(source, || REQUESTS.try_send(request).is_ok())
    })
}

/// The oldest waiting request that goes ahead, else the oldest other (control task side).
pub fn take() -> Option<Datagram> {
    LANES.lock(|lanes| {
        let lanes = &mut *lanes.borrow_mut();
        if let Ok(request) = AHEAD.try_receive() {
            lanes.ahead.release(request.peer.ip());
            return Some(request);
        }
        let request = REQUESTS.try_receive().ok()?;
        lanes.requests.release(request.peer.ip());
        Some(request)
    })
}
