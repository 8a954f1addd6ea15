//! Replay protection: which signed timestamps are still new, also across restarts.
//!
//! * **Per link.** A link id's timestamps must increase: one slot per possible link id (256),
//!   so no link is ever evicted (an evicted link would accept its old datagrams again).
//! * **A link's first.** A link not yet used since the start takes a timestamp only within
//!   [`FIRST_WINDOW`] of the newest served on any link, so a captured sequence is not a
//!   library of replays on every link not yet used.
//! * **Across restarts.** Before a timestamp above the kept *reservation* is served, the
//!   reservation is raised to it plus [`RESERVE_AHEAD`] and kept ([`ReplayStore`]: a state
//!   file, the board's flash), so the kept value is always at least every timestamp served.
//!   At the start nothing at or below it is served. A store is written at most once per
//!   [`RESERVE_AHEAD`] of the clients' clocks, and a restart refuses signed requests (stops
//!   excepted) for at most that long after the last write.

use armgate_protocol::client::signed::{Signature, TIMESTAMP_MAX};

/// How far a link's first timestamp may lie behind the newest served (60 s in 10 µs steps).
pub const FIRST_WINDOW: u64 = 6_000_000;

/// How far ahead of a served timestamp the kept reservation goes: the wire's rule (clients
/// resend for that long after a restart's refusal).
pub use armgate_protocol::client::signed::RESERVE_AHEAD;

/// Where the reservation survives a restart: what the shell provides (`armgate-sim`'s state
/// file, the firmware's flash or file). Called from the tick, at most once per
/// [`RESERVE_AHEAD`] of timestamps: a write must be short.
pub trait ReplayStore {
    /// The reservation kept before the start (0: none, a new controller).
    fn load(&mut self) -> u64;
    /// Keeps `reserved` (every timestamp served is at most it). `false`: not kept (counted;
    /// the request is served all the same, and a restart may then replay what followed).
    fn keep(&mut self, reserved: u64) -> bool;
}

/// No store: every start is a new controller (the tests, the benches, a controller without a
/// key).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Unkept;

impl ReplayStore for Unkept {
    fn load(&mut self) -> u64 {
        0
    }

    fn keep(&mut self, _: u64) -> bool {
        true
    }
}

/// A store or none (a shell whose store is an option: `armgate-sim` without a key).
impl<T: ReplayStore> ReplayStore for Option<T> {
    fn load(&mut self) -> u64 {
        self.as_mut().map_or(0, ReplayStore::load)
    }

    fn keep(&mut self, reserved: u64) -> bool {
        self.as_mut().is_none_or(|store| store.keep(reserved))
    }
}

/// Whether a signed request's timestamp is new.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Freshness {
    /// New: served, and the replay state moves on.
    New,
    /// Not new (replayed, a clock gone back, older than the window or than a restart).
    Old,
}

/// The timestamps: per link the lowest one still new, the newest served, the controller's own.
#[derive(Clone, Debug)]
pub(super) struct Replay {
    /// Per link id, the last timestamp served + 1 (0: none since the start).
    floors: [u64; 256],
    /// The newest timestamp served on any link (at the start, the kept reservation).
    newest: u64,
    /// Nothing below it is served: the kept reservation at the start, + 1.
    started: u64,
    /// The reservation kept in the store.
    reserved: u64,
    /// The controller's timestamp: the last it signed with, raised to every request served.
    clock: u64,
    /// Reservations the store could not keep.
    pub store_failures: u32,
}

impl Replay {
    /// The state after a start whose store kept `reserved`.
    pub fn new(reserved: u64) -> Self {
        Self {
            floors: [0; 256],
            newest: reserved,
            started: reserved.saturating_add(u64::from(reserved > 0)),
            reserved,
            clock: reserved,
            store_failures: 0,
        }
    }

    /// Whether `signature`'s timestamp is new; if it is, the state moves on (and the
    /// reservation, kept in `store` first when the timestamp passes it).
    pub fn accept(&mut self, signature: Signature, store: &mut impl ReplayStore) -> Freshness {
        let t = signature.timestamp;
        let Some(floor) = self.floors.get_mut(usize::from(signature.link)) else {
            return Freshness::Old;
        };
        let new = t >= self.started
            && match *floor {
                0 => t.saturating_add(FIRST_WINDOW) >= self.newest,
                floor => t >= floor,
            };
        if !new {
            return Freshness::Old;
        }
        *floor = t.saturating_add(1);
        self.newest = self.newest.max(t);
        if t > self.reserved {
            self.reserved = t.saturating_add(RESERVE_AHEAD).min(TIMESTAMP_MAX);
            if !store.keep(self.reserved) {
                self.store_failures = self.store_failures.saturating_add(1);
            }
        }
        // Answers are never older than a request served, so a client can refuse old ones.
        self.clock = self.clock.max(t.saturating_sub(1));
        Freshness::New
    }

    /// The timestamp of the controller's next signature.
    pub fn tick_clock(&mut self) -> u64 {
        self.clock = self.clock.saturating_add(1).min(TIMESTAMP_MAX);
        self.clock
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A store that records what it was asked to keep.
    #[derive(Default)]
    struct Kept(Vec<u64>);

    impl ReplayStore for Kept {
        fn load(&mut self) -> u64 {
            self.0.last().copied().unwrap_or(0)
        }
        fn keep(&mut self, reserved: u64) -> bool {
            self.0.push(reserved);
            true
        }
    }

    const DAY: u64 = 86_400 * 100_000;
    const NOW: u64 = 3_500 * DAY;

    fn on(link: u8, timestamp: u64) -> Signature {
        Signature { link, timestamp }
    }

    #[test]
    fn a_link_first_timestamp_must_be_within_a_minute_of_the_newest() {
        let mut store = Kept::default();
        let mut replay = Replay::new(0);
        // A fresh controller takes any first timestamp.
        assert_eq!(replay.accept(on(1, NOW), &mut store), Freshness::New);
        assert_eq!(replay.accept(on(1, NOW), &mut store), Freshness::Old);
        // A day-old datagram on an unused link: old. One 59 s behind: new.
        assert_eq!(replay.accept(on(2, NOW - DAY), &mut store), Freshness::Old);
        assert_eq!(
            replay.accept(on(3, NOW - FIRST_WINDOW - 1), &mut store),
            Freshness::Old
        );
        assert_eq!(
            replay.accept(on(3, NOW - FIRST_WINDOW), &mut store),
            Freshness::New
        );
        // Once used, a link goes on from its own last (behind the newest is fine).
        assert_eq!(
            replay.accept(on(3, NOW - FIRST_WINDOW + 1), &mut store),
            Freshness::New
        );
    }

    #[test]
    fn the_reservation_is_kept_before_serving_past_it_and_refuses_everything_up_to_it() {
        let mut store = Kept::default();
        let mut replay = Replay::new(store.load());
        for k in 0..100 {
            // 100 requests 10 ms apart: 1 s of use, one write.
            assert_eq!(
                replay.accept(on(1, NOW + k * 1000), &mut store),
                Freshness::New
            );
        }
        assert_eq!(store.0, [NOW + RESERVE_AHEAD]);
        assert_eq!(
            replay.accept(on(1, NOW + RESERVE_AHEAD + 1), &mut store),
            Freshness::New
        );
        assert_eq!(store.0, [NOW + RESERVE_AHEAD, NOW + 2 * RESERVE_AHEAD + 1]);
        // A restart: nothing served before is served again, on any link, nor anything up to
        // the reservation; after it, the clients' clocks go on.
        let mut restarted = Replay::new(store.load());
        for link in [1, 2, 200] {
            for t in [NOW, NOW + RESERVE_AHEAD + 1, NOW + 2 * RESERVE_AHEAD + 1] {
                assert_eq!(restarted.accept(on(link, t), &mut store), Freshness::Old);
            }
        }
        assert_eq!(
            restarted.accept(on(2, NOW + 2 * RESERVE_AHEAD + 2), &mut store),
            Freshness::New
        );
        assert!(restarted.tick_clock() > NOW + 2 * RESERVE_AHEAD + 1);
        assert_eq!(restarted.store_failures, 0);
    }
}
