//! Signed clients by link id: with a key the session follows the link id, not the source
//! address (a source address proves nothing, and anyone may send from the holder's).
//!
//! A signed request reaches the command handler as from its link's *identity*, the address
//! `0.0.0.N`, port 0, for link N (`0.0.0.0/8` is "this network", never a datagram's source, and
//! an IPv4 address is cheap to compare in the session's scans): the session, the watchdog and
//! the resend check then know the client by its link id, and an unsigned datagram — from any
//! address, the holder's included — is another client. `ER40` names a signed holder
//! `by 0.0.0.N`, its link id. The
//! table here maps each link id back to the address it was last heard from: where its answers
//! and notices go, signed. It also notices two sources interleaved on one link id (two
//! clients that chose the same link id), counted for `SQ` index 6.

/// The identity of a signed link and back: the wire's rule (`0.0.0.N`, port 0).
pub(super) use armgate_protocol::client::signed::{
    link_identity as identity, link_of_identity as link_of,
};

use super::link::Peer;

/// Links remembered at once; a new one replaces the one heard from longest ago (never the
/// holder's).
pub const LINKS: usize = 16;

/// The first link id set aside for a client that asks for one: above the small ones people
/// type (`--link-id 1`, 2, ...).
const FIRST_FREE: u8 = 101;

/// A source heard on a link within this long of another is a second client on it (s).
pub const SHARED_WITHIN: f64 = 1.0;

/// A link's last source, the one before it, and when it was heard.
#[derive(Clone, Copy, Debug)]
struct Entry<P> {
    link: u8,
    peer: P,
    before: Option<P>,
    heard: f64,
}

/// The links heard, and the shared ones counted.
#[derive(Clone, Debug)]
pub(super) struct Links<P> {
    entries: [Option<Entry<P>>; LINKS],
    /// Signed datagrams that came on a link from the source before its last, within
    /// [`SHARED_WITHIN`] of the last: two sources interleaved.
    pub shared: u32,
    /// The last link seen shared (0: none).
    pub last_shared: u8,
    /// Where the search for a free link starts next.
    next_free: u8,
    /// When a shared link was last announced (s): at most one notice per [`SHARED_WITHIN`].
    announced: Option<f64>,
}

impl<P: Peer> Links<P> {
    pub fn new() -> Self {
        Self {
            entries: [None; LINKS],
            shared: 0,
            last_shared: 0,
            next_free: FIRST_FREE,
            announced: None,
        }
    }

    /// True if a shared link seen at `now` is to be announced (a notice): at most once per
    /// [`SHARED_WITHIN`], however fast two clients interleave.
    pub fn announce(&mut self, now: f64) -> bool {
        let due = self.announced.is_none_or(|at| now - at > SHARED_WITHIN);
        if due {
            self.announced = Some(now);
        }
        due
    }

    /// A link id not in the table, set aside for `peer` at `now` (as if heard from it), so
    /// that the next client to ask gets another; 0 if every one is taken. `keep` as for
    /// [`heard`](Self::heard). The search goes round from where the last one ended.
    pub fn set_aside(&mut self, peer: P, now: f64, keep: Option<u8>) -> u8 {
        for _ in 0..u8::MAX {
            let link = self.next_free;
            self.next_free = if link == u8::MAX { 1 } else { link + 1 };
            if self.peer(link).is_none() {
                self.heard(link, peer, now, keep);
                return link;
            }
        }
        0
    }

    /// Notes that `link` was heard from `peer` at `now`; `keep` is the holder's link (never
    /// replaced). True if two sources interleave on it: `peer` is the one before the last, and
    /// the last was heard within [`SHARED_WITHIN`]. (A client that moved to a new port, A then
    /// B, is not counted; A, B, A is.)
    pub fn heard(&mut self, link: u8, peer: P, now: f64, keep: Option<u8>) -> bool {
        let same = |p: Option<P>| p.is_some_and(|p| p.address() == peer.address());
        let found = self
            .entries
            .iter()
            .position(|e| e.is_some_and(|e| e.link == link));
        let last = found.and_then(|k| self.entries.get(k).copied().flatten());
        let (shared, before) = match last {
            Some(e) if same(Some(e.peer)) => (false, e.before),
            Some(e) => (
                same(e.before) && now - e.heard <= SHARED_WITHIN,
                Some(e.peer),
            ),
            None => (false, None),
        };
        let slot = found.or_else(|| self.free_or_oldest(now, keep));
        if let Some(entry) = slot.and_then(|k| self.entries.get_mut(k)) {
            *entry = Some(Entry {
                link,
                peer,
                before,
                heard: now,
            });
        }
        if shared {
            self.shared = self.shared.saturating_add(1);
            self.last_shared = link;
        }
        shared
    }

    /// Where link `link`'s answers and notices go.
    pub fn peer(&self, link: u8) -> Option<P> {
        self.entries
            .iter()
            .flatten()
            .find(|e| e.link == link)
            .map(|e| e.peer)
    }

    fn free_or_oldest(&self, now: f64, keep: Option<u8>) -> Option<usize> {
        let age = |e: &Option<Entry<P>>| match e {
            None => f64::INFINITY,
            Some(e) if Some(e.link) == keep => f64::NEG_INFINITY,
            Some(e) => now - e.heard,
        };
        let mut oldest: Option<(usize, f64)> = None;
        for (k, e) in self.entries.iter().enumerate() {
            let a = age(e);
            if oldest.is_none_or(|(_, o)| a > o) {
                oldest = Some((k, a));
            }
        }
        oldest.map(|(k, _)| k)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::net::SocketAddr;

    fn at(last: u8, port: u16) -> SocketAddr {
        SocketAddr::from(([192, 168, 1, last], port))
    }

    #[test]
    fn identities_hold_the_link_id_and_no_real_address_is_one() {
        for link in [1, 7, 255] {
            assert_eq!(link_of(identity(link)), Some(link));
        }
        assert_eq!(link_of(at(2, 0)), None);
        assert_eq!(link_of("0.0.0.7:5000".parse().unwrap()), None);
        assert_eq!(link_of("0.0.1.7:0".parse().unwrap()), None);
        assert_eq!(
            link_of("0.0.0.0:0".parse().unwrap()),
            None,
            "no address: ()"
        );
        assert_eq!(link_of("[::7]:0".parse().unwrap()), None);
    }

    #[test]
    fn a_link_follows_its_last_source_and_two_interleaved_ones_are_counted() {
        let mut links: Links<SocketAddr> = Links::new();
        assert!(!links.heard(1, at(2, 5000), 0.0, None));
        assert!(!links.heard(1, at(2, 5000), 0.1, None));
        // A restarted client, on a new port, a while later: the same link, not shared.
        assert!(!links.heard(1, at(2, 5001), 5.0, None));
        assert_eq!(links.peer(1), Some(at(2, 5001)));
        // A second client on link 1: counted when the sources interleave.
        assert!(!links.heard(1, at(3, 6000), 5.2, None));
        assert!(links.heard(1, at(2, 5001), 5.3, None));
        assert!(links.heard(1, at(3, 6000), 5.4, None));
        assert!(!links.heard(1, at(3, 6000), 5.5, None));
        assert_eq!((links.shared, links.last_shared), (2, 1));
        // Said at most once a second.
        assert!(links.announce(5.3));
        assert!(!links.announce(5.4));
        assert!(links.announce(6.4));
        // The table is bounded and keeps the holder's link.
        for k in 0..100u8 {
            links.heard(
                k.saturating_add(2),
                at(9, u16::from(k)),
                10.0 + f64::from(k),
                Some(1),
            );
        }
        assert!(links.peer(1).is_some());
        assert_eq!(links.peer(2), None, "replaced");
    }

    #[test]
    fn links_set_aside_are_free_and_never_the_same_twice_in_a_row() {
        let mut links: Links<SocketAddr> = Links::new();
        links.heard(FIRST_FREE, at(2, 1), 0.0, None);
        let first = links.set_aside(at(3, 1), 0.1, None);
        let second = links.set_aside(at(4, 1), 0.1, None);
        assert_eq!((first, second), (FIRST_FREE + 1, FIRST_FREE + 2));
        assert_eq!(links.peer(first), Some(at(3, 1)));
        // Round past 255 to 1.
        links.next_free = u8::MAX;
        assert_eq!(links.set_aside(at(5, 1), 0.2, None), u8::MAX);
        assert_eq!(links.set_aside(at(5, 1), 0.2, None), 1);
    }
}
