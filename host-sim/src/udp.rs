//! The client port of `armgate-sim`: a non-blocking UDP socket behind the allow-list, as the
//! cycle's [`Link`]. Datagrams and replies are logged here.

use std::io::ErrorKind;
use std::net::{SocketAddr, UdpSocket};

use armgate_core::command::Network;
use armgate_core::cycle::{Datagram, Dropped, Link, Outgoing};

use crate::log::{Logger, Record};

/// Datagrams read per [`Link::receive`] call at most while skipping foreign sources.
const MAX_SKIPPED: usize = 256;

/// Counters shown in the status line and at exit.
#[derive(Debug, Default)]
pub struct Stats {
    /// Requests from allowed sources.
    pub received: u64,
    /// Datagrams from sources not allowed (dropped).
    pub refused_sources: u64,
}

/// The socket, the allow-list and the log, for one tick at a time.
pub struct UdpLink<'a> {
    /// The socket (non-blocking).
    pub socket: &'a UdpSocket,
    /// Its local address, for the capture (`--pcap`).
    pub local: SocketAddr,
    /// Who may command the arm.
    pub allow: &'a [Network],
    /// The CSV logs.
    pub logger: &'a Logger,
    /// What was counted.
    pub stats: &'a mut Stats,
    /// Wall-clock time of the tick, for the log (s).
    pub time: f64,
    /// A receive error other than "nothing waiting": the shell stops with it.
    pub error: Option<String>,
}

impl Link<SocketAddr> for UdpLink<'_> {
    fn receive(&mut self) -> Option<Datagram<SocketAddr>> {
        let mut buf = [0u8; 64];
        for _ in 0..MAX_SKIPPED {
            let (len, from) = match self.socket.recv_from(&mut buf) {
                Ok(received) => received,
                Err(e) if e.kind() == ErrorKind::WouldBlock => return None,
                Err(e) => {
                    self.error = Some(format!("udp receive: {e}"));
                    return None;
                }
            };
            // Captured before the allow-list: a refused client is what one looks for in a
            // capture.
            crate::pcap::udp(from, self.local, buf.get(..len).unwrap_or(&[]));
            crate::record::request(from, self.local, buf.get(..len).unwrap_or(&[]));
            if !self.allow.iter().any(|net| net.contains(from.ip())) {
                self.stats.refused_sources += 1;
                continue;
            }
            self.stats.received += 1;
            let datagram = buf.get(..len).unwrap_or(&[]);
            self.logger.log(Record::Command {
                t: self.time,
                datagram: datagram.to_vec(),
            });
            return Some(Datagram::new(datagram, from));
        }
        None
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
