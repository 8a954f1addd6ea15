//! The client port of `armgate-sim`: a non-blocking UDP socket behind the allow-list, as the
//! cycle's [`Link`]. Datagrams and replies are logged here.
//!
//! Each [`Link::receive`] first reads what the socket holds (up to [`MAX_READS`]) into an
//! [`Inbox`] with a queue per source address, and takes the requests from the sources in
//! turn: a client flooding the simulator waits behind its own requests only, and the others'
//! requests, a stop among them, are handled in the next tick. (The firmware, with a queue of
//! 8, gives each source half of it; a burst from one client is answered whole here, as the
//! kernel's 4 MiB buffer held it before.) A full inbox makes room by dropping the newest
//! request of the source that holds the most, so a flood from many addresses cannot shut the
//! others out, and stops and the holder's requests ([`goes_ahead`]) are taken first.

use std::collections::VecDeque;
use std::io::ErrorKind;
use std::net::{IpAddr, SocketAddr, UdpSocket};

use armgate_core::command::Network;
use armgate_core::cycle::{Datagram, Dropped, Link, Outgoing, goes_ahead};

use crate::log::{Logger, Record};

/// Datagrams read from the socket per [`Link::receive`] call at most.
const MAX_READS: usize = 256;

/// Requests waiting in the [`Inbox`] at most (about what the 4 MiB socket buffer holds).
const INBOX_CAPACITY: usize = 4096;

/// Requests that go ahead taken per tick at most (as the firmware's queue for them holds): the
/// rest of the tick's are taken in turn, so that a holder that floods does not shut out the
/// others.
pub const AHEAD_PER_TICK: usize = 4;

/// Requests read and waiting for a tick: a queue per source address, taken in turn.
#[derive(Debug, Default)]
pub struct Inbox {
    /// The sources with waiting requests, the next to be served first.
    sources: VecDeque<(IpAddr, VecDeque<Datagram<SocketAddr>>)>,
    /// Requests waiting, all sources together.
    len: usize,
}

/// What became of a request offered to the [`Inbox`].
#[derive(Debug, PartialEq)]
enum Admission {
    /// Queued.
    Queued,
    /// Queued, and the newest request of the source that held the most was dropped for it.
    QueuedInstead,
    /// Dropped: the inbox is full, and its source holds as many as any.
    Dropped,
}

impl Inbox {
    /// Queues `datagram` behind its source's; with the inbox full, in place of the newest
    /// request of the source that holds the most, if that one holds more than this one's.
    fn push(&mut self, datagram: Datagram<SocketAddr>) -> Admission {
        let source = datagram.peer.ip();
        let mut admission = Admission::Queued;
        if self.len >= INBOX_CAPACITY {
            let held = self
                .sources
                .iter()
                .find(|(ip, _)| *ip == source)
                .map_or(0, |(_, queue)| queue.len());
            match self.sources.iter_mut().max_by_key(|(_, queue)| queue.len()) {
                Some((_, longest)) if longest.len() > held + 1 => {
                    longest.pop_back();
                    self.len -= 1;
                    admission = Admission::QueuedInstead;
                }
                _ => return Admission::Dropped,
            }
        }
        match self.sources.iter_mut().find(|(ip, _)| *ip == source) {
            Some((_, queue)) => queue.push_back(datagram),
            None => self.sources.push_back((source, VecDeque::from([datagram]))),
        }
        self.len += 1;
        admission
    }

    /// With `ahead`, the oldest request of the first source in turn whose next request goes
    /// ahead (a stop, or from `holder`), if any; else that of the next source in turn. True
    /// with the request if it went ahead.
    fn pop(&mut self, holder: Option<IpAddr>, ahead: bool) -> Option<(Datagram<SocketAddr>, bool)> {
        let first = ahead
            .then(|| {
                self.sources.iter().position(|(ip, queue)| {
                    queue
                        .front()
                        .is_some_and(|d| goes_ahead(d.payload(), *ip, holder))
                })
            })
            .flatten();
        let (source, mut queue) = self.sources.remove(first.unwrap_or(0))?;
        let datagram = queue.pop_front();
        if !queue.is_empty() {
            self.sources.push_back((source, queue));
        }
        self.len -= usize::from(datagram.is_some());
        datagram.map(|d| (d, first.is_some()))
    }
}

/// Counters shown in the status line and at exit.
#[derive(Debug, Default)]
pub struct Stats {
    /// Requests from allowed sources.
    pub received: u64,
    /// Datagrams from sources not allowed (dropped).
    pub refused_sources: u64,
    /// Requests dropped because the inbox was full.
    pub crowded: u64,
}

/// The socket, the allow-list and the log, for one tick at a time.
pub struct UdpLink<'a> {
    /// The socket (non-blocking).
    pub socket: &'a UdpSocket,
    /// Its local address, for the capture (`--pcap`).
    pub local: SocketAddr,
    /// Who may command the arm.
    pub allow: &'a [Network],
    /// Requests read and not yet handled.
    pub inbox: &'a mut Inbox,
    /// The address of the client that holds the arm (its requests are taken first).
    pub holder: Option<IpAddr>,
    /// Requests that went ahead this tick ([`AHEAD_PER_TICK`] at most).
    pub ahead_taken: usize,
    /// The CSV logs.
    pub logger: &'a Logger,
    /// What was counted.
    pub stats: &'a mut Stats,
    /// Wall-clock time of the tick, for the log (s).
    pub time: f64,
    /// A receive error other than "nothing waiting": the shell stops with it.
    pub error: Option<String>,
}

impl UdpLink<'_> {
    /// Reads what the socket holds (at most [`MAX_READS`]) into the inbox.
    fn read_socket(&mut self) {
        let mut buf = [0u8; 64];
        for _ in 0..MAX_READS {
            let (len, from) = match self.socket.recv_from(&mut buf) {
                Ok(received) => received,
                Err(e) if e.kind() == ErrorKind::WouldBlock => return,
                Err(e) => {
                    self.error = Some(format!("udp receive: {e}"));
                    return;
                }
            };
            // Captured before the allow-list: a refused client is what one looks for in a
            // capture.
            let datagram = buf.get(..len).unwrap_or(&[]);
            crate::pcap::udp(from, self.local, datagram);
            crate::record::request(from, self.local, datagram);
            if !self.allow.iter().any(|net| net.contains(from.ip())) {
                self.stats.refused_sources += 1;
                continue;
            }
            match self.inbox.push(Datagram::new(datagram, from)) {
                Admission::Queued => {}
                Admission::QueuedInstead => self.stats.crowded += 1,
                Admission::Dropped => {
                    self.stats.crowded += 1;
                    continue;
                }
            }
            self.stats.received += 1;
            self.logger.log(Record::Command {
                t: self.time,
                datagram: datagram.to_vec(),
            });
        }
    }
}

impl Link<SocketAddr> for UdpLink<'_> {
    fn receive(&mut self) -> Option<Datagram<SocketAddr>> {
        self.read_socket();
        let ahead = self.ahead_taken < AHEAD_PER_TICK;
        let (datagram, went_ahead) = self.inbox.pop(self.holder, ahead)?;
        self.ahead_taken += usize::from(went_ahead);
        Some(datagram)
    }

    fn send(&mut self, datagram: &Datagram<SocketAddr>, kind: Outgoing) -> Result<(), Dropped> {
        let bytes = datagram.payload();
        let record = match kind {
            Outgoing::Reply => {
                let mut reply = [0u8; armgate_protocol::client::MESSAGE_LEN];
                for (r, b) in reply.iter_mut().zip(bytes) {
                    *r = *b;
                }
                Record::Reply {
                    t: self.time,
                    datagram: reply,
                }
            }
            Outgoing::Notice => Record::Warning {
                t: self.time,
                text: String::from_utf8_lossy(bytes)
                    .trim_end_matches('\0')
                    .to_string(),
            },
        };
        self.logger.log(record);
        // A lost datagram is no reason to stop the arm; UDP gives no guarantee anyway. The
        // cycle counts it.
        let sent = self.socket.send_to(bytes, datagram.peer);
        if sent.is_ok() {
            crate::pcap::udp(self.local, datagram.peer, bytes);
            crate::record::answer(self.local, datagram.peer, bytes);
        }
        sent.map(drop).map_err(|_| Dropped)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ps(ip: [u8; 4]) -> Datagram<SocketAddr> {
        Datagram::new(b"PS", SocketAddr::from((ip, 4000)))
    }

    #[test]
    fn a_full_inbox_drops_from_the_source_that_holds_the_most() {
        let mut inbox = Inbox::default();
        for k in 0..INBOX_CAPACITY {
            let ip = [10, 0, (k % 64) as u8, if k < 64 { 1 } else { 2 }];
            assert_eq!(inbox.push(ps(ip)), Admission::Queued);
        }
        // 10.0.x.1 hold one each, 10.0.x.2 (4096 - 64) / 64 = 63: a new source, or one that
        // holds one, gets in in place of one of the latter's; one of those does not.
        assert_eq!(inbox.push(ps([10, 1, 0, 1])), Admission::QueuedInstead);
        assert_eq!(inbox.len, INBOX_CAPACITY);
        assert_eq!(inbox.push(ps([10, 0, 0, 1])), Admission::QueuedInstead);
        assert_eq!(inbox.push(ps([10, 0, 5, 2])), Admission::Dropped);
        assert_eq!(inbox.len, INBOX_CAPACITY);
    }

    #[test]
    fn stops_and_the_holders_requests_are_taken_first() {
        let mut inbox = Inbox::default();
        let holder = [192, 168, 1, 2];
        for k in 1..=20 {
            inbox.push(ps([192, 168, 1, 100 + k]));
        }
        inbox.push(Datagram::new(
            b"ST",
            SocketAddr::from(([192, 168, 1, 9], 1)),
        ));
        inbox.push(ps(holder));
        inbox.push(ps(holder));
        let mut pop = |ahead| inbox.pop(Some(holder.into()), ahead).unwrap();
        let (first, ahead) = pop(true);
        assert_eq!((first.payload(), ahead), (&b"ST"[..], true));
        let (second, ahead) = pop(true);
        assert_eq!((second.peer.ip(), ahead), (IpAddr::from(holder), true));
        // Not ahead (its tick's share is taken): the next source in turn.
        let (third, ahead) = pop(false);
        assert_eq!(
            (third.peer.ip(), ahead),
            (IpAddr::from([192, 168, 1, 101]), false)
        );
        let (fourth, _) = pop(true);
        assert_eq!(fourth.peer.ip(), IpAddr::from(holder));
    }
}
