//! A cycle's clients in a test: the requests queued for its next tick, and its replies.

use std::collections::VecDeque;
use std::net::SocketAddr;

use armgate_core::cycle::{Datagram, Dropped, Link, Outgoing};

/// Requests queued for the next tick, and what came back.
#[derive(Default)]
pub struct Clients {
    pub requests: VecDeque<Datagram<SocketAddr>>,
    pub replies: Vec<(SocketAddr, String)>,
}

impl Link<SocketAddr> for Clients {
    fn receive(&mut self) -> Option<Datagram<SocketAddr>> {
        self.requests.pop_front()
    }

    fn send(&mut self, datagram: &Datagram<SocketAddr>, kind: Outgoing) -> Result<(), Dropped> {
        if kind == Outgoing::Reply {
            self.replies
                .push((datagram.peer, reply_text(datagram.payload())));
        }
        Ok(())
    }
}

/// A reply as text: an `ER`/`WN` text, or the reply's two characters.
pub fn reply_text(reply: &[u8]) -> String {
    let text = String::from_utf8_lossy(reply)
        .trim_end_matches('\0')
        .to_owned();
    if text.starts_with("ER") || text.starts_with("WN") {
        text
    } else {
        String::from_utf8_lossy(&reply[..2]).into_owned()
    }
}
