//! The client port of `armgate-sim`: a non-blocking UDP socket behind the allow-list, as the
//! cycle's [`Link`]. Datagrams and replies are logged here.
//!
//! Each [`Link::receive`] first reads what the socket holds (up to [`MAX_READS`]) into an
//! [`Inbox`] with a queue per source address, and takes the requests from the sources in
//! turn: a client flooding the simulator waits behind its own requests only, and the others'
//! requests, a stop among them, are handled in the next tick. (The firmware, with a queue of
//! 8, gives each source half of it; a burst from one client is answered whole here, as the
//! kernel's 4 MiB buffer held it before.)

use std::collections::VecDeque;
use std::io::ErrorKind;
use std::net::{IpAddr, SocketAddr, UdpSocket};

use armgate_core::command::Network;
use armgate_core::cycle::{Datagram, Dropped, Link, Outgoing};

use crate::log::{Logger, Record};

/// Datagrams read from the socket per [`Link::receive`] call at most.
const MAX_READS: usize = 256;

/// Requests waiting in the [`Inbox`] at most (about what the 4 MiB socket buffer holds).
const INBOX_CAPACITY: usize = 4096;

/// Requests read and waiting for a tick: a queue per source address, taken in turn.
#[derive(Debug, Default)]
pub struct Inbox {
    /// The sources with waiting requests, the next to be served first.
    sources: VecDeque<(IpAddr, VecDeque<Datagram<SocketAddr>>)>,
    /// Requests waiting, all sources together.
    len: usize,
}

impl Inbox {
    /// Queues `datagram` behind its source's; false if the inbox is full.
    fn push(&mut self, datagram: Datagram<SocketAddr>) -> bool {
        if self.len >= INBOX_CAPACITY {
            return false;
        }
        let source = datagram.peer.ip();
        match self.sources.iter_mut().find(|(ip, _)| *ip == source) {
            Some((_, queue)) => queue.push_back(datagram),
            None => self.sources.push_back((source, VecDeque::from([datagram]))),
        }
        self.len += 1;
        true
    }

    /// The oldest request of the next source in turn.
    fn pop(&mut self) -> Option<Datagram<SocketAddr>> {
        let (source, mut queue) = self.sources.pop_front()?;
        let datagram = queue.pop_front();
        if !queue.is_empty() {
            self.sources.push_back((source, queue));
        }
        self.len -= usize::from(datagram.is_some());
        datagram
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
            if !self.inbox.push(Datagram::new(datagram, from)) {
                self.stats.crowded += 1;
                continue;
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
        self.inbox.pop()
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
