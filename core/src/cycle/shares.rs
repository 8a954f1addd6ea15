//! Fair shares of a shell's request queue: one source address holds at most half of it.
//!
//! A shell queues requests before the cycle handles them ([`REQUESTS_PER_TICK`] a tick). If
//! one client could fill that queue, a flood from it would crowd out everyone else's requests,
//! a stop among them. With a share per source, the others always find room, and their requests
//! are handled within a tick or two of arriving.
//!
//! Shares alone cannot keep room when more sources flood than the queue has places: it is
//! full whenever a request arrives. Some requests therefore go ahead ([`goes_ahead`]): a
//! stop, obeyed from everyone, and the requests of the client that holds the arm. A shell
//! queues them apart and serves them first.
//!
//! [`REQUESTS_PER_TICK`]: super::REQUESTS_PER_TICK

use core::net::IpAddr;

use armgate_protocol::client::Command;

use crate::command::Class;

/// True if the request `payload` from `source` goes ahead of the others: a stop (`ST`, `jR`),
/// or any request from `holder`, the address of the client that holds the arm.
pub fn goes_ahead(payload: &[u8], source: IpAddr, holder: Option<IpAddr>) -> bool {
    matches!(payload, [a, b, ..] if is_stop(Command::from_chars([*a, *b])))
        || holder == Some(source)
}

/// True if `payload` is the reply to a stop (`TS`, `Rj`), which a shell sends ahead of other
/// replies to new destinations.
pub fn answers_a_stop(payload: &[u8]) -> bool {
    matches!(payload, [a, b, ..] if is_stop(Command::from_reply_chars([*a, *b])))
}

/// True if `command` is a stop.
fn is_stop(command: Option<Command>) -> bool {
    command.is_some_and(|c| Class::of(c) == Class::Stop)
}

/// How many requests of a queue of `N` each source address holds, for at most `N` sources.
#[derive(Clone, Debug)]
pub struct Shares<const N: usize> {
    held: [Option<(IpAddr, usize)>; N],
}

impl<const N: usize> Default for Shares<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Shares<N> {
    /// Requests one source may hold: half the queue (at least one).
    pub const PER_SOURCE: usize = if N / 2 > 0 { N / 2 } else { 1 };

    /// Nobody holds anything.
    pub const fn new() -> Self {
        Self { held: [None; N] }
    }

    /// Queues a request from `source` with `push` (false: the queue is full) if `source` holds
    /// fewer than [`PER_SOURCE`](Self::PER_SOURCE); true if it was queued.
    pub fn admit(&mut self, source: IpAddr, push: impl FnOnce() -> bool) -> bool {
        let held = self.held.iter().flatten().find(|(a, _)| *a == source);
        if held.is_some_and(|(_, n)| *n >= Self::PER_SOURCE) || !push() {
            return false;
        }
        let own = self
            .held
            .iter()
            .position(|e| matches!(e, Some((a, _)) if *a == source));
        // Every queued request holds an entry: with room in the queue, one is free.
        let entry = match own {
            Some(k) => self.held.get_mut(k),
            None => self.held.iter_mut().find(|e| e.is_none()),
        };
        if let Some(entry) = entry {
            let n = entry.map_or(0, |(_, n)| n);
            *entry = Some((source, n.saturating_add(1)));
        }
        true
    }

    /// How many requests `source` holds.
    pub fn held(&self, source: IpAddr) -> usize {
        self.held
            .iter()
            .flatten()
            .find(|(a, _)| *a == source)
            .map_or(0, |(_, n)| *n)
    }

    /// A request from `source` left the queue.
    pub fn release(&mut self, source: IpAddr) {
        if let Some(entry) = self
            .held
            .iter_mut()
            .find(|e| matches!(e, Some((a, _)) if *a == source))
        {
            *entry = entry.and_then(|(a, n)| (n > 1).then_some((a, n - 1)));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::net::Ipv4Addr;

    #[test]
    fn a_flooding_source_fills_only_its_half() {
        let flood = IpAddr::V4(Ipv4Addr::new(192, 168, 1, 9));
        let operator = IpAddr::V4(Ipv4Addr::new(192, 168, 1, 2));
        let mut shares = Shares::<8>::new();
        let mut queued = 0;
        let admitted = (0..100)
            .filter(|_| {
                shares.admit(flood, || {
                    queued += 1;
                    true
                })
            })
            .count();
        assert_eq!((admitted, queued), (4, 4));
        assert!(shares.admit(operator, || true));
        // Taking one of the flood's lets one more in, no more.
        shares.release(flood);
        assert!(shares.admit(flood, || true));
        assert!(!shares.admit(flood, || true));
        // A full queue admits nobody, and counts nothing.
        assert!(!shares.admit(operator, || false));
        shares.release(operator);
        for _ in 0..4 {
            shares.release(flood);
        }
        assert!(shares.held.iter().all(Option::is_none));
    }

    #[test]
    fn stops_and_the_holders_requests_go_ahead() {
        let holder = IpAddr::V4(Ipv4Addr::new(192, 168, 1, 2));
        let other = IpAddr::V4(Ipv4Addr::new(192, 168, 1, 9));
        assert!(goes_ahead(b"ST", other, Some(holder)));
        assert!(goes_ahead(b"jR\0\0", other, None));
        assert!(goes_ahead(b"PS", holder, Some(holder)));
        assert!(goes_ahead(b"", holder, Some(holder)));
        assert!(!goes_ahead(b"PS", other, Some(holder)));
        assert!(!goes_ahead(b"CM", other, None));
        assert!(!goes_ahead(b"S", other, None));
        assert!(!goes_ahead(b"TS", other, None));
        assert!(answers_a_stop(b"TS"));
        assert!(answers_a_stop(b"Rj\0"));
        assert!(!answers_a_stop(b"ST"));
        assert!(!answers_a_stop(b"SP"));
        assert!(!answers_a_stop(b"ER40 Cmd ST"));
        assert!(!answers_a_stop(b"T"));
    }

    #[test]
    fn held_counts_a_sources_requests() {
        let a = IpAddr::V4(Ipv4Addr::new(10, 0, 0, 1));
        let mut shares = Shares::<8>::new();
        assert_eq!(shares.held(a), 0);
        assert!(shares.admit(a, || true));
        assert!(shares.admit(a, || true));
        assert_eq!(shares.held(a), 2);
        shares.release(a);
        assert_eq!(shares.held(a), 1);
    }
}
