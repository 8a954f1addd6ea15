//! [`Cycle`]: one control tick, the same in every shell (the policy is in the module docs).

use super::budget::{PLANNING_PER_TICK, Pending, SLICE, Waiting, Work, cancel_motion, waits};
use super::counters::bump;
use super::links::{Links, identity, link_of};
use super::replay::{ReplayStore, Unkept};
use super::signing::{Gate, is_identity_request};
use super::{CycleCounters, Datagram, DriveSide, Link, Outgoing, Peer, Signing};
use crate::command::{CommandHandler, NOTICE_CAPACITY};
use crate::config::ValidRobot;
use crate::kinematics::KinematicsError;
use crate::motion::StepOutput;
use armgate_protocol::client::signed::{IdentityReport, SigningReport};
use armgate_protocol::client::{MESSAGE_LEN, Notice};
use core::net::SocketAddr;
use core::num::NonZeroU64;

/// Client requests handled per tick at most; more wait for the next tick. A client waits for
/// each reply, so this leaves room for several clients and for bursts, and bounds the tick.
pub const REQUESTS_PER_TICK: usize = 8;

/// A tick at most this many periods late is still run (the shell calls back to back until it
/// has caught up); later ones are skipped.
pub const MAX_CATCH_UP: u64 = 50;

/// What one tick did, for the shell's log and status line.
#[derive(Clone, Debug)]
pub struct TickOutcome {
    /// The tick's time on the schedule (s since the cycle started).
    pub time: f64,
    /// Ticks skipped before this one because the call came more than [`MAX_CATCH_UP`]
    /// periods late (usually 0).
    pub skipped: u64,
    /// The control step's result (an error made the drives hold).
    pub step: Result<StepOutput, KinematicsError>,
}

/// The command handler and the drives, ticked on a fixed schedule.
///
/// `P` is the shell's peer address (a socket address, an embassy endpoint); `S` keeps the
/// signed timestamps' reservation across restarts ([`ReplayStore`]; none by default).
#[derive(Clone, Debug)]
pub struct Cycle<D, P, S = Unkept> {
    handler: CommandHandler,
    drives: D,
    /// The control period (s), and in whole microseconds for the shell's clock.
    period: f64,
    period_us: NonZeroU64,
    /// Index of the next tick on the schedule.
    next: u64,
    /// Time of the previous tick (s).
    previous: Option<f64>,
    counters: CycleCounters,
    /// Requests the work budget left for a later tick.
    waiting: Waiting<P>,
    /// The planning request whose work runs, one slice a tick (a `KG`'s search, a `BG`'s line
    /// check): answered when it ends.
    planning: Option<Pending<P>>,
    /// The signature checks every datagram passes first.
    gate: Gate,
    /// Where the replay reservation is kept.
    store: S,
    /// Signed clients by link id: where their answers and notices go.
    links: Links<P>,
}

impl<D: DriveSide, P: Peer> Cycle<D, P> {
    /// A cycle for a validated robot description with `drives`, before its first tick.
    pub fn new(config: &ValidRobot, drives: D) -> Self {
        // The period is validated finite and positive; the cast saturates for absurd values.
        let period_us = libm::round(config.control_period * 1e6) as u64;
        Self {
            handler: CommandHandler::new(config),
            drives,
            period: config.control_period,
            period_us: NonZeroU64::new(period_us).unwrap_or(NonZeroU64::MIN),
            next: 0,
            previous: None,
            counters: CycleCounters::default(),
            waiting: Waiting::new(),
            planning: None,
            gate: Gate::new(Signing::default(), 0),
            store: Unkept,
            links: Links::new(),
        }
    }
}

impl<D: DriveSide, P: Peer, S: ReplayStore> Cycle<D, P, S> {
    /// The same cycle with these signing settings (a key for this controller, what unsigned
    /// datagrams may do), after the reservation its store kept.
    pub fn with_signing(mut self, signing: Signing) -> Self {
        let reserved = self.store.load();
        self.gate = Gate::new(signing, reserved);
        self.handler.set_signing_report(self.gate.report());
        self.handler.set_identity(self.identity());
        self
    }

    /// The same cycle, keeping the replay reservation in `store` across restarts. Give it
    /// before [`with_signing`](Self::with_signing), which reads what `store` kept.
    pub fn with_store<T: ReplayStore>(self, store: T) -> Cycle<D, P, T> {
        Cycle {
            handler: self.handler,
            drives: self.drives,
            period: self.period,
            period_us: self.period_us,
            next: self.next,
            previous: self.previous,
            counters: self.counters,
            waiting: self.waiting,
            planning: self.planning,
            gate: self.gate,
            store,
            links: self.links,
        }
    }

    /// The controller's id and the shared links seen (`SQ` index 6).
    pub fn identity(&self) -> IdentityReport {
        IdentityReport {
            controller: self.gate.controller(),
            shared_links: self.links.shared,
            last_shared: self.links.last_shared,
            free_link: 0,
        }
    }

    /// The replay store (a shell reads its errors).
    pub fn store_mut(&mut self) -> &mut S {
        &mut self.store
    }

    /// Reservations the replay store could not keep (each a window in which a restart could
    /// serve a replay); 0 without a store.
    pub fn store_failures(&self) -> u32 {
        self.gate.store_failures()
    }

    /// When the next tick is due on the shell's clock (µs since the cycle started).
    pub fn next_due_us(&self) -> u64 {
        self.next.saturating_mul(self.period_us.get())
    }

    /// The control period in whole microseconds (at least 1).
    pub fn period_us(&self) -> u64 {
        self.period_us.get()
    }

    /// Runs the next tick on the schedule; `now_us` is the shell's clock (µs since the cycle
    /// started). Called early, the tick runs at its scheduled time all the same. Called a whole
    /// period or more late, it still runs (and is counted): the shell calls again at once until
    /// [`next_due_us`](Self::next_due_us) is ahead of its clock. More than [`MAX_CATCH_UP`]
    /// periods late, the missed ticks are skipped.
    pub fn tick(&mut self, now_us: u64, link: &mut impl Link<P>) -> TickOutcome {
        let due = self.next_due_us();
        let behind = now_us.saturating_sub(due) / self.period_us;
        let mut skipped = 0;
        if behind > MAX_CATCH_UP {
            skipped = behind;
            self.counters.skipped_ticks = self.counters.skipped_ticks.saturating_add(skipped);
            self.next = self.next.saturating_add(skipped);
        } else if behind > 0 {
            bump(&mut self.counters.late_ticks);
        }
        let time = self.next as f64 * self.period;
        let elapsed = self.previous.map_or(self.period, |t| time - t);
        self.next = self.next.saturating_add(1);
        self.previous = Some(time);
        bump(&mut self.counters.ticks);

        if !self.drives.receive(time) {
            bump(&mut self.counters.tick_errors);
        }
        let step = self
            .handler
            .tick(time, &self.drives.measured(), &mut self.drives);
        let command = step.as_ref().map(|out| out.command.as_ref());
        if command.is_err() {
            bump(&mut self.counters.tick_errors);
        }
        self.drives.transmit(time, elapsed, command.ok().flatten());
        self.handle_requests(link, time);
        self.send_notices(link);
        TickOutcome {
            time,
            skipped,
            step,
        }
    }

    /// The command handler (the controller's mode, pose, motion).
    pub fn handler(&self) -> &CommandHandler {
        &self.handler
    }

    /// The command handler, mutable (test rigs and benches that command the controller
    /// directly).
    pub fn handler_mut(&mut self) -> &mut CommandHandler {
        &mut self.handler
    }

    /// The drives.
    pub fn drives(&self) -> &D {
        &self.drives
    }

    /// The drives, mutable.
    pub fn drives_mut(&mut self) -> &mut D {
        &mut self.drives
    }

    /// What the cycle counted.
    pub fn counters(&self) -> CycleCounters {
        self.counters
    }

    /// Where notices go: the client that holds the arm, or the last one that sent a valid
    /// request (a signed client: where its link was last heard from).
    pub fn notice_recipient(&self) -> Option<P> {
        self.peer_of(self.handler.notice_recipient()?)
    }

    /// The client that holds the arm ([`goes_ahead`](super::goes_ahead) serves its requests
    /// first).
    pub fn holder(&self) -> Option<P> {
        self.peer_of(self.handler.holder()?)
    }

    /// The peer of a session client: a signed link's last source, or the address itself.
    fn peer_of(&self, client: SocketAddr) -> Option<P> {
        match link_of(client) {
            Some(link) => self.links.peer(link),
            None => Some(P::from_address(client)),
        }
    }

    /// The signing policy and counters (served, dropped by cause): `SQ` index 4.
    pub fn signing(&self) -> SigningReport {
        self.gate.report()
    }

    /// Answers one request from `peer` between ticks (protocol tests), the work of a planning
    /// request (a `KG`'s search, a `BG`'s line check) run to its end at once. [`tick`](Self::tick) answers the requests its link delivers.
    // Out of line: request handling (parsing, planning moves and sequences, replies) is rare
    // and large; inlined, it would sit in the tick's code and stack frame.
    #[inline(never)]
    pub fn answer(&mut self, datagram: &[u8], peer: P) -> [u8; MESSAGE_LEN] {
        bump(&mut self.counters.requests);
        let drives = &mut self.drives;
        self.handler
            .handle_at_once(datagram, peer.address(), drives)
    }

    /// Answers one request from the session's `client` (a signed link's identity, or an
    /// address).
    #[inline(never)]
    fn answer_from(&mut self, datagram: &[u8], client: SocketAddr) -> [u8; MESSAGE_LEN] {
        bump(&mut self.counters.requests);
        self.handler.handle_from(datagram, client, &mut self.drives)
    }

    fn handle_requests(&mut self, link: &mut impl Link<P>, now: f64) {
        let drops = self.counters.send_dropped.saturating_add(link.dropped());
        self.handler.set_send_drops(drops);
        // The work budget (module `budget`): requests waiting from earlier ticks first; work
        // in slices (a `KG`'s search, a `BG`'s line check) takes the tick's planning slot.
        let mut planned = usize::from(self.planning.is_some());
        let mut later = Waiting::new();
        for _ in 0..REQUESTS_PER_TICK {
            let request = match self.waiting.pop_front() {
                Some(waiting) => waiting,
                None => {
                    let Some(datagram) = link.receive() else {
                        break;
                    };
                    // Dropped datagrams are counted by the gate and never answered.
                    let Some(admitted) = self.gate.admit(datagram.payload(), &mut self.store)
                    else {
                        continue;
                    };
                    // A signed link's holder, for the link table (it never drops the holder's).
                    let holder = admitted.link.and(self.handler.holder()).and_then(link_of);
                    if let Some(signed) = admitted.link
                        && self.links.heard(signed, datagram.peer, now, holder)
                        && self.links.announce(now)
                    {
                        self.handler.announce(Notice::LinkShared(signed));
                    }
                    // The identity report is read only by `SQ` 6: built for it alone.
                    if is_identity_request(admitted.message) {
                        let mut identity = self.identity();
                        if admitted.link.is_some() {
                            // A link of its own for a client that starts (it may take it).
                            identity.free_link = self.links.set_aside(datagram.peer, now, holder);
                        }
                        self.handler.set_identity(identity);
                    }
                    self.handler.set_signing_report(self.gate.report());
                    Pending {
                        datagram: Datagram::new(admitted.message, datagram.peer),
                        link: admitted.link,
                    }
                }
            };
            let work = Work::of(request.datagram.payload());
            let plans = matches!(work, Work::Plans(_));
            // A stop waits for nothing, not even its own client's requests: it cancels them.
            let peer = request.datagram.peer;
            let behind_planning = self
                .planning
                .is_some_and(|s| s.datagram.peer.address() == peer.address());
            let queued = work != Work::Stops && (behind_planning || waits(&later, peer));
            if queued || (plans && planned >= PLANNING_PER_TICK) {
                // Room: at most one a pass.
                let _ = later.push_back(request);
                continue;
            }
            planned += usize::from(plans);
            if work == Work::Stops {
                self.cancel_waiting(&mut later, link);
            }
            let client = request
                .link
                .map_or(request.datagram.peer.address(), identity);
            let reply = self.answer_from(request.datagram.payload(), client);
            if self.handler.planning_started() {
                self.planning = Some(request);
            } else {
                self.reply(link, &reply, &request);
            }
        }
        if let Some(request) = self.planning
            && let Some(reply) =
                self.handler
                    .continue_planning(SLICE, request.datagram.payload(), &self.drives)
        {
            self.planning = None;
            self.reply(link, &reply, &request);
        }
        // What waited before stays ahead of what the link still holds. (Together never more
        // than the queue: with some left in `waiting`, every pass took one from it.)
        while let Some(request) = self.waiting.pop_front() {
            let _ = later.push_back(request);
        }
        self.waiting = later;
    }

    /// Answers the requests waiting (in `later` and in `waiting`) that would start motion as
    /// cancelled by a stop that arrived after them.
    fn cancel_waiting(&mut self, later: &mut Waiting<P>, link: &mut impl Link<P>) {
        let mut cancelled = Waiting::new();
        for queue in [&mut *later, &mut self.waiting] {
            cancel_motion(queue, |request| {
                let _ = cancelled.push_back(request);
            });
        }
        if let Some(request) = self.planning.take() {
            self.handler.cancel_planning();
            self.cancel(link, &request);
        }
        while let Some(request) = cancelled.pop_front() {
            self.cancel(link, &request);
        }
    }

    /// Answers `request` as cancelled by a stop.
    fn cancel(&mut self, link: &mut impl Link<P>, request: &Pending<P>) {
        self.handler.count_refusal();
        if let Some(command) = Work::of(request.datagram.payload()).cancelled_by_stop() {
            let reply = Notice::Cancelled(command).text().to_bytes();
            self.reply(link, &reply, request);
        }
    }

    /// Sends `reply` to the client of `request`, sealed if the request was signed.
    fn reply(&mut self, link: &mut impl Link<P>, reply: &[u8; MESSAGE_LEN], request: &Pending<P>) {
        let sealed = self.gate.seal(reply, request.link.is_some());
        let peer = request.datagram.peer;
        self.send(link, Datagram::new(sealed.bytes(), peer), Outgoing::Reply);
    }

    fn send_notices(&mut self, link: &mut impl Link<P>) {
        for _ in 0..NOTICE_CAPACITY {
            let Some(text) = self.handler.next_notice() else {
                break;
            };
            // Signed to a signed client (a link's identity), unsigned to an address.
            let recipient = self.handler.notice_recipient();
            let signed = recipient.and_then(link_of).is_some();
            match recipient.and_then(|r| self.peer_of(r)) {
                Some(peer) => {
                    bump(&mut self.counters.notices);
                    let sealed = self.gate.seal(&text.to_bytes(), signed);
                    self.send(link, Datagram::new(sealed.bytes(), peer), Outgoing::Notice);
                }
                None => bump(&mut self.counters.notices_unaddressed),
            }
        }
    }

    fn send(&mut self, link: &mut impl Link<P>, datagram: Datagram<P>, kind: Outgoing) {
        if link.send(&datagram, kind).is_err() {
            bump(&mut self.counters.send_dropped);
        }
    }
}
