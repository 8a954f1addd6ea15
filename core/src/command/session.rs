//! Who is talking: the clients the controller knows (a bounded table), the one that controls
//! the arm, and where unsolicited notices go.
//!
//! * **One controlling client.** Requests that command the arm — motion, mode, power,
//!   recalibration, goals, via points and blends ([`Class::Command`]) — come from the client
//!   that holds the arm. While the arm moves or streams, another client's are refused
//!   (`ER40 Cmd XX by <address>`); at rest, another client's takes control (so a restarted
//!   client, or one on a new port, just works).
//! * **A stop from anyone.** `ST` (and `jR`) are obeyed from every allowed client, always.
//! * **Reads for everyone.** `PS`, `jP`, `TM`, `SQ` are answered to every client.
//! * **Notices** go to the holder, or with none to the last client that sent a valid request;
//!   a datagram that does not parse changes nothing.
//! * **Resends are idempotent.** A motion start (`BG`, `jB`, `VE`, `jE`) repeated byte for
//!   byte by the same client within [`RESEND_WINDOW`] of its reply (the client's reply was
//!   lost) gets that reply again and is not carried out twice. Every other request is the same
//!   done once or twice (reads, stops, goals, modes, power) or meant to repeat (the streams
//!   `TW`, `jW`), and a refused one changed nothing: those are carried out every time.
//!
//! * **A client watchdog.** The holder may ask for one (`WD`, ms; 0 off): while the arm moves
//!   and the holder has sent nothing for longer, the arm is stopped as by `ST` with the notice
//!   `ER41 client silent N ms` ([`Session::silent`]). It ends with the holder's control.
//!
//! A source address proves nothing about the sender (docs/safety.md): this keeps honest tools
//! from overriding each other, it is no defence against a forger on the network.

use core::net::{IpAddr, SocketAddr};

use armgate_protocol::client::{Command, Holder, MESSAGE_LEN, Notice, SessionReport, Severity};

/// Clients the controller keeps track of; a new one replaces the one heard from longest ago
/// (never the holder).
pub const CLIENTS: usize = 8;

/// How long after a reply the same datagram from the same client is a resend (s).
pub const RESEND_WINDOW: f64 = 1.0;

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
            Command::Pose
            | Command::JointPosition
            | Command::Temperature
            | Command::Status
            | Command::IkSolution => Self::Read,
            Command::Stop | Command::JointReset => Self::Stop,
            _ => Self::Command,
        }
    }
}

/// A client: its source address, when it was last heard (s, the controller's time), and its
/// last request with the reply it got, if that reply may be sent again.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Client {
    address: SocketAddr,
    heard: f64,
    last: Option<Exchange>,
}

/// A request (its first 31 bytes and length) and its reply.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Exchange {
    request: [u8; MESSAGE_LEN],
    len: usize,
    /// The reply, if the request is one whose reply a resend gets again.
    reply: Option<[u8; MESSAGE_LEN]>,
    at: f64,
}

impl Exchange {
    fn new(datagram: &[u8], reply: Option<[u8; MESSAGE_LEN]>, at: f64) -> Self {
        let mut request = [0; MESSAGE_LEN];
        let mut len = 0;
        for (r, b) in request.iter_mut().zip(datagram) {
            *r = *b;
            len += 1;
        }
        Self {
            request,
            len,
            reply,
            at,
        }
    }

    fn is(&self, datagram: &[u8]) -> bool {
        datagram.len().min(MESSAGE_LEN) == self.len
            && self.request.get(..self.len) == datagram.get(..self.len)
    }
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
    /// The holder's watchdog (ms), if on.
    watchdog: Option<u16>,
    /// The watchdog stopped the arm, and the holder has not been heard since.
    tripped: bool,
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
            Some(holder) if holder != client && busy => Err(Notice::HeldBy(command, ipv4(holder))),
            Some(holder) if holder == client => Ok(()),
            _ => {
                self.holder = Some(client);
                self.watchdog = None;
                Ok(())
            }
        }
    }

    /// Sets the holder's watchdog to `ms` (0: off); the request was admitted, so the sender
    /// holds the arm.
    pub fn set_watchdog(&mut self, ms: u16) {
        self.watchdog = (ms > 0).then_some(ms);
    }

    /// The holder's watchdog time (ms) if it has run out at `now`: the holder has been silent
    /// for longer. Once per silence: the next request from the holder rearms it.
    pub fn silent(&mut self, now: f64) -> Option<u16> {
        let ms = self.watchdog?;
        let holder = self.find(self.holder?)?;
        let silent = now - holder.heard > f64::from(ms) * 1e-3;
        if !silent || self.tripped {
            return None;
        }
        self.tripped = true;
        Some(ms)
    }

    /// The reply `client` got for `datagram`, if this is a resend of its last request within
    /// [`RESEND_WINDOW`] of that reply at `now`.
    pub fn resent(
        &self,
        client: SocketAddr,
        datagram: &[u8],
        now: f64,
    ) -> Option<[u8; MESSAGE_LEN]> {
        let last = self.find(client)?.last?;
        (last.is(datagram) && now - last.at <= RESEND_WINDOW)
            .then_some(last.reply)
            .flatten()
    }

    /// Records the reply `client` got at `now` for the valid request `datagram` of `command`.
    pub fn answered(
        &mut self,
        client: SocketAddr,
        command: Command,
        datagram: &[u8],
        reply: &[u8; MESSAGE_LEN],
        now: f64,
    ) {
        // Only a motion start done twice differs from done once (the second is `busy`, or a
        // second move); a refused one changed nothing and may now succeed.
        let [c0, c1, ..] = *reply;
        let refused = Severity::from_prefix([c0, c1]).is_some();
        let repeatable = matches!(
            command,
            Command::Begin | Command::JointBegin | Command::ViaExecute | Command::JointExecute
        ) && !refused;
        let exchange = Exchange::new(datagram, repeatable.then_some(*reply), now);
        if let Some(entry) = self
            .clients
            .iter_mut()
            .flatten()
            .find(|c| c.address == client)
        {
            entry.last = Some(exchange);
        }
    }

    fn find(&self, client: SocketAddr) -> Option<&Client> {
        self.clients.iter().flatten().find(|c| c.address == client)
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
            watchdog_ms: self.watchdog.map_or(0, u32::from),
            send_drops: u32::try_from(self.send_drops).unwrap_or(u32::MAX),
            clients: u8::try_from(self.clients.iter().flatten().count()).unwrap_or(u8::MAX),
        }
    }

    /// Notes that `client` was heard at `now`, in its own entry, a free one, or the one heard
    /// from longest ago that is not the holder.
    fn hear(&mut self, client: SocketAddr, now: f64) {
        let holder = self.holder;
        if holder == Some(client) {
            self.tripped = false;
        }
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
            let last = entry.filter(|c| c.address == client).and_then(|c| c.last);
            *entry = Some(Client {
                address: client,
                heard: now,
                last,
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
            Err(Notice::HeldBy(Command::ChangeMode, Some([192, 168, 1, 2])))
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
    fn a_resent_command_gets_its_reply_again_within_a_second() {
        let (a, b) = (at(2, 5000), at(3, 6000));
        let mut s = Session::default();
        let begin = *b"BG\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0";
        let reply = *b"GB\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0";
        s.admit(Command::Begin, a, 0.0, false).unwrap();
        s.answered(a, Command::Begin, &begin, &reply, 0.0);
        assert_eq!(s.resent(a, &begin, 0.2), Some(reply));
        assert_eq!(
            s.resent(a, &begin, 1.1),
            None,
            "a second later it is a new request"
        );
        assert_eq!(
            s.resent(b, &begin, 0.2),
            None,
            "another client's is its own"
        );
        assert_eq!(
            s.resent(a, &begin[..30], 0.2),
            None,
            "not the same datagram"
        );
        // Another request in between: the next BG is new.
        s.admit(Command::Stop, a, 0.3, true).unwrap();
        s.answered(a, Command::Stop, b"ST", &[0; MESSAGE_LEN], 0.3);
        assert_eq!(s.resent(a, &begin, 0.4), None);
        // A refusal changed nothing: the same request is carried out again.
        s.admit(Command::Begin, a, 0.4, false).unwrap();
        s.answered(
            a,
            Command::Begin,
            &begin,
            &Notice::HeldBy(Command::Begin, None).text().to_bytes(),
            0.4,
        );
        assert_eq!(s.resent(a, &begin, 0.45), None);
        // Reads and streams are carried out every time.
        s.admit(Command::Twist, a, 0.5, false).unwrap();
        s.answered(a, Command::Twist, b"TW", &[1; MESSAGE_LEN], 0.5);
        assert_eq!(s.resent(a, b"TW", 0.5), None);
        s.admit(Command::Pose, a, 0.6, false).unwrap();
        s.answered(a, Command::Pose, b"PS", &[1; MESSAGE_LEN], 0.6);
        assert_eq!(s.resent(a, b"PS", 0.6), None);
    }

    #[test]
    fn the_watchdog_trips_once_per_silence_of_the_holder_and_ends_with_its_control() {
        let (a, b) = (at(2, 5000), at(3, 6000));
        let mut s = Session::default();
        s.admit(Command::Watchdog, a, 0.0, false).unwrap();
        s.set_watchdog(500);
        assert_eq!(s.report(a).watchdog_ms, 500);
        // Another client's polls do not feed it.
        s.admit(Command::Pose, b, 0.4, true).unwrap();
        assert_eq!(s.silent(0.45), None);
        assert_eq!(s.silent(0.51), Some(500));
        assert_eq!(s.silent(0.6), None, "once");
        s.admit(Command::Pose, a, 0.7, false).unwrap();
        assert_eq!(s.silent(1.0), None);
        assert_eq!(s.silent(1.21), Some(500));
        // A new holder starts without one.
        s.admit(Command::On, b, 2.0, false).unwrap();
        assert_eq!(s.silent(9.0), None);
        assert_eq!(s.report(b).watchdog_ms, 0);
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
