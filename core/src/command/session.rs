//! Who is talking: the clients the controller knows (a bounded table), the one that controls
//! the arm, and where unsolicited notices go.
//!
//! * **One controlling client.** Requests that command the arm — motion, mode, power,
//!   recalibration, goals, via points and blends ([`Class::Command`]) — come from the client
//!   that holds the arm. While the arm moves or streams, another client's are refused
//!   (`ER40 held by <address>`); at rest, another client's takes control (so a restarted
//!   client, or one on a new port, just works).
//! * **A stop from anyone.** `ST` (and `jR`) are obeyed from every allowed client, always.
//! * **Reads for everyone.** `PS`, `jP`, `TM`, `SQ` are answered to every client.
//! * **Notices** go to the holder, or with none to the last client that sent a valid request;
//!   a datagram that does not parse changes nothing.
//!
//! A source address proves nothing about the sender (docs/safety.md): this keeps honest tools
//! from overriding each other, it is no defence against a forger on the network.

use core::net::{IpAddr, SocketAddr};

use armgate_protocol::client::{Command, Holder, Notice, SessionReport};

/// Clients the controller keeps track of; a new one replaces the one heard from longest ago
/// (never the holder).
pub const CLIENTS: usize = 8;

/// What a request may do, and so who may send it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Class {
    /// Reads state: answered to everyone.
    Read,
    /// Stops the arm: obeyed from everyone.
    Stop,
    /// Commands the arm: only from the holder while the arm moves.
    Command,
}

impl Class {
    /// The class of `command`.
    pub fn of(command: Command) -> Self {
        match command {
            Command::Pose | Command::JointPosition | Command::Temperature | Command::Status => {
                Self::Read
            }
            Command::Stop | Command::JointReset => Self::Stop,
            _ => Self::Command,
        }
    }
}

/// A client: its source address and when it was last heard (s, the controller's time).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Client {
    address: SocketAddr,
    heard: f64,
}

/// The clients, the holder, the notice recipient.
#[derive(Clone, Debug, Default)]
pub struct Session {
    clients: [Option<Client>; CLIENTS],
    holder: Option<SocketAddr>,
    /// The last client that sent a valid request.
    last: Option<SocketAddr>,
    /// Replies and notices the shell could not send (the shell's count).
    send_drops: u64,
}

impl Session {
    /// Admits a valid request of `command` from `client` at `now`, `busy` while the arm moves
    /// or streams: takes control for a command request when it may, refuses it when another
    /// client holds the arm and it is busy.
    pub fn admit(
        &mut self,
        command: Command,
        client: SocketAddr,
        now: f64,
        busy: bool,
    ) -> Result<(), Notice> {
        self.hear(client, now);
        self.last = Some(client);
        if Class::of(command) != Class::Command {
            return Ok(());
        }
        match self.holder {
            Some(holder) if holder != client && busy => Err(Notice::HeldBy(ipv4(holder))),
            _ => {
                self.holder = Some(client);
                Ok(())
            }
        }
    }

    /// Where notices go: the holder, or the last client that sent a valid request.
    pub fn notice_recipient(&self) -> Option<SocketAddr> {
        self.holder.or(self.last)
    }

    /// The client that holds the arm.
    pub fn holder(&self) -> Option<SocketAddr> {
        self.holder
    }

    /// The shell's count of replies and notices it could not send.
    pub fn set_send_drops(&mut self, drops: u64) {
        self.send_drops = drops;
    }

    /// The session as `asking` sees it (`SQ` index 3).
    pub fn report(&self, asking: SocketAddr) -> SessionReport {
        SessionReport {
            holder: match self.holder {
                None => Holder::Nobody,
                Some(h) if h == asking => Holder::You,
                Some(_) => Holder::Other,
            },
            address: match self.holder {
                Some(SocketAddr::V4(a)) => Some(a),
                _ => None,
            },
            watchdog_ms: 0,
            send_drops: u32::try_from(self.send_drops).unwrap_or(u32::MAX),
            clients: u8::try_from(self.clients.iter().flatten().count()).unwrap_or(u8::MAX),
        }
    }

    /// Notes that `client` was heard at `now`, in its own entry, a free one, or the one heard
    /// from longest ago that is not the holder.
    fn hear(&mut self, client: SocketAddr, now: f64) {
        let holder = self.holder;
        let age = |e: &Option<Client>| match e {
            Some(c) if c.address == client => f64::INFINITY,
            Some(c) if Some(c.address) == holder => f64::NEG_INFINITY,
            Some(c) => now - c.heard,
            None => f64::MAX,
        };
        let mut oldest: Option<&mut Option<Client>> = None;
        for entry in &mut self.clients {
            if oldest.as_ref().is_none_or(|o| age(entry) > age(o)) {
                oldest = Some(entry);
            }
        }
        if let Some(entry) = oldest {
            *entry = Some(Client {
                address: client,
                heard: now,
            });
        }
    }
}

/// The address of `client` for a refusal text, if it is IPv4.
fn ipv4(client: SocketAddr) -> Option<[u8; 4]> {
    match client.ip() {
        IpAddr::V4(ip) => Some(ip.octets()),
        IpAddr::V6(_) => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(last: u8, port: u16) -> SocketAddr {
        SocketAddr::from(([192, 168, 1, last], port))
    }

    #[test]
    fn one_client_holds_the_arm_while_it_moves_and_any_may_stop_it() {
        let (a, b) = (at(2, 5000), at(3, 6000));
        let mut s = Session::default();
        assert_eq!(s.admit(Command::Begin, a, 0.0, false), Ok(()));
        assert_eq!(s.holder(), Some(a));
        // B reads and stops while A's move runs; its commands are refused with A's address.
        assert_eq!(s.admit(Command::Pose, b, 0.1, true), Ok(()));
        assert_eq!(
            s.admit(Command::ChangeMode, b, 0.1, true),
            Err(Notice::HeldBy(Some([192, 168, 1, 2])))
        );
        assert_eq!(
            s.admit(Command::GoalRpy, b, 0.1, true)
                .map_err(|n| n.code()),
            Err(40)
        );
        assert_eq!(s.admit(Command::Stop, b, 0.2, true), Ok(()));
        assert_eq!((s.holder(), s.notice_recipient()), (Some(a), Some(a)));
        // At rest, B takes control with its next command.
        assert_eq!(s.admit(Command::JointBegin, b, 0.3, false), Ok(()));
        assert_eq!(s.holder(), Some(b));
        assert_eq!(s.report(b).holder, Holder::You);
        assert_eq!(s.report(a).holder, Holder::Other);
        assert_eq!(
            s.report(a).address,
            Some("192.168.1.3:6000".parse().unwrap())
        );
    }

    #[test]
    fn notices_go_to_the_last_valid_sender_until_someone_holds_the_arm() {
        let (a, b) = (at(2, 5000), at(3, 6000));
        let mut s = Session::default();
        assert_eq!(s.notice_recipient(), None);
        s.admit(Command::Pose, a, 0.0, false).unwrap();
        s.admit(Command::Status, b, 0.0, false).unwrap();
        assert_eq!(s.notice_recipient(), Some(b));
        s.admit(Command::On, a, 0.1, false).unwrap();
        s.admit(Command::Status, b, 0.2, false).unwrap();
        assert_eq!(s.notice_recipient(), Some(a));
    }

    #[test]
    fn the_table_is_bounded_and_keeps_the_holder() {
        let holder = at(1, 1);
        let mut s = Session::default();
        s.admit(Command::On, holder, 0.0, false).unwrap();
        for k in 0..100u16 {
            s.admit(Command::Pose, at(9, 1000 + k), 1.0 + f64::from(k), true)
                .unwrap();
        }
        assert_eq!(usize::from(s.report(holder).clients), CLIENTS);
        assert!(s.clients.iter().flatten().any(|c| c.address == holder));
        assert_eq!(s.report(holder).holder, Holder::You);
    }
}
