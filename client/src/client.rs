//! The UDP client: one request, one reply, with timeout, retries and a notice queue.

use std::collections::VecDeque;
use std::io::ErrorKind;
use std::net::{Ipv4Addr, Ipv6Addr, SocketAddr, ToSocketAddrs, UdpSocket};
use std::time::{Duration, Instant};

use armgate_protocol::client::signed::{
    IDENTITY_INDEX, IdentityReport, RESERVE_AHEAD, TIMESTAMP_UNIT_US,
};
use armgate_protocol::client::{Command, MESSAGE_LEN, Message, Reply, Request, Text, VALUES};

use crate::ClientError;
use crate::matching::{Expect, Incoming, classify_unsolicited};
use crate::signer::Signer;

/// The controller's default address (`armgate-sim` listens here).
pub const DEFAULT_ADDR: &str = "127.0.0.1:7031";

/// How long to wait for the reply after each send, by default.
pub const DEFAULT_TIMEOUT: Duration = Duration::from_millis(200);

/// How many times a request is re-sent after the first send timed out, by default.
pub const DEFAULT_RETRIES: u32 = 3;

/// How many unsolicited notices are kept, by default (the oldest is dropped first).
pub const DEFAULT_NOTICE_CAPACITY: usize = 64;

/// Timeouts, retries and the notice queue's size.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ClientConfig {
    /// How long to wait for the reply after each send.
    pub timeout: Duration,
    /// How many times the same datagram is re-sent when no reply came (so a request is sent at
    /// most `1 + retries` times).
    pub retries: u32,
    /// How many unsolicited notices are kept until [`Client::take_notices`].
    pub notice_capacity: usize,
}

impl Default for ClientConfig {
    fn default() -> Self {
        Self {
            timeout: DEFAULT_TIMEOUT,
            retries: DEFAULT_RETRIES,
            notice_capacity: DEFAULT_NOTICE_CAPACITY,
        }
    }
}

/// A reply as received, for requests whose characters are not a known [`Command`]
/// (see [`Client::send_raw`]).
///
/// [`Command`]: armgate_protocol::client::Command
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RawReply {
    /// The reply's two characters.
    pub chars: [u8; 2],
    /// f0..f6.
    pub values: [f32; VALUES],
    /// The index byte.
    pub index: u8,
    /// The whole datagram (replies that carry text, like the `SQ` name, are read from it).
    pub bytes: [u8; MESSAGE_LEN],
}

/// A client of one controller, on a UDP socket bound to an ephemeral local port.
///
/// Requests are strictly one at a time: [`request`](Self::request) sends a datagram and waits for
/// its reply (see [`matching`](crate::matching) for how the reply is recognised). Unsolicited
/// `ER`/`WN` texts that arrive meanwhile are kept in a bounded queue; drain it with
/// [`take_notices`](Self::take_notices).
#[derive(Debug)]
pub struct Client {
    socket: UdpSocket,
    peer: SocketAddr,
    config: ClientConfig,
    notices: VecDeque<Text>,
    dropped_notices: u64,
    stale_replies: u64,
    /// Signs requests and checks answers, if set.
    signer: Option<Signer>,
    /// The timestamp of the last request signed: no answer may be older.
    signed_at: u64,
    /// Datagrams dropped because they were not signed with the key, or older.
    unverified: u64,
}

impl Client {
    /// Connects to the controller at `addr` (e.g. `127.0.0.1:7031`) with the default
    /// [`ClientConfig`]. Nothing is sent: UDP has no handshake.
    pub fn connect(addr: impl ToSocketAddrs) -> Result<Self, ClientError> {
        Self::connect_with(addr, ClientConfig::default())
    }

    /// Connects to the controller at `addr` with the given timeouts and retries.
    pub fn connect_with(
        addr: impl ToSocketAddrs,
        config: ClientConfig,
    ) -> Result<Self, ClientError> {
        let peer = addr
            .to_socket_addrs()
            .map_err(|e| {
                ClientError::Address(format!("{e}: expected host:port, e.g. {DEFAULT_ADDR}"))
            })?
            .next()
            .ok_or_else(|| ClientError::Address("the address resolves to nothing".into()))?;
        let local: SocketAddr = if peer.is_ipv4() {
            (Ipv4Addr::UNSPECIFIED, 0).into()
        } else {
            (Ipv6Addr::UNSPECIFIED, 0).into()
        };
        let socket = UdpSocket::bind(local)?;
        // A connected socket receives only the controller's datagrams.
        socket.connect(peer)?;
        Ok(Self {
            socket,
            peer,
            config,
            notices: VecDeque::new(),
            dropped_notices: 0,
            stale_replies: 0,
            signer: None,
            signed_at: 0,
            unverified: 0,
        })
    }

    /// Signs every request from now on with `signer`, and accepts only answers signed with
    /// its key (`None`: unsigned, as the seed's protocol).
    pub fn set_signer(&mut self, signer: Option<Signer>) {
        self.signer = signer;
    }

    /// The signer, if requests are signed.
    pub fn signer(&self) -> Option<&Signer> {
        self.signer.as_ref()
    }

    /// The controller's identity report (`SQ` index 6). With a signer that does not know the
    /// controller's id yet, the request is signed for any controller and the signer takes the
    /// id the signed answer names, and the link id set aside for it unless it was given; every
    /// request does this first while they are unknown.
    pub fn identify(&mut self) -> Result<IdentityReport, ClientError> {
        let reply = self.request(Request {
            command: Command::Status,
            values: [0.0; VALUES],
            index: IDENTITY_INDEX,
        })?;
        let report = IdentityReport::from_reply(&reply)
            .map_err(|e| ClientError::InvalidArgument(format!("SQ {IDENTITY_INDEX}: {e}")))?;
        if let Some(signer) = &mut self.signer {
            signer.identified(&report);
        }
        Ok(report)
    }

    /// How many datagrams were dropped because they were not signed with the key, or were
    /// older than the request they could answer (forged, replayed, another key).
    pub fn unverified(&self) -> u64 {
        self.unverified
    }

    /// The controller's address.
    pub fn peer(&self) -> SocketAddr {
        self.peer
    }

    /// The local address the socket is bound to.
    pub fn local_addr(&self) -> Result<SocketAddr, ClientError> {
        Ok(self.socket.local_addr()?)
    }

    /// The timeouts and retries in use.
    pub fn config(&self) -> &ClientConfig {
        &self.config
    }

    /// Sends `request` and waits for its reply.
    ///
    /// Each send waits [`ClientConfig::timeout`] for the reply; with no reply the same datagram
    /// is sent again, up to [`ClientConfig::retries`] more times. An `ER` text that answers the
    /// request is [`ClientError::Rejected`]; unsolicited notices are queued and the wait goes on.
    pub fn request(&mut self, request: Request) -> Result<Reply, ClientError> {
        let bytes = request.to_bytes();
        let expect = Expect {
            chars: request.command.chars(),
            index: request.index,
        };
        let reply = self.exchange(&bytes, expect)?;
        let message = Message::new_checked(&reply[..])
            .map_err(|e| ClientError::InvalidArgument(e.to_string()))?;
        Reply::parse(&message).map_err(|e| ClientError::InvalidArgument(e.to_string()))
    }

    /// Sends any two characters with seven values and an index (the seed's text client: it can
    /// send a pair the controller does not know, to see its `ER00`). The reply is matched as
    /// for [`request`](Self::request).
    pub fn send_raw(
        &mut self,
        chars: [u8; 2],
        values: [f32; VALUES],
        index: u8,
    ) -> Result<RawReply, ClientError> {
        let mut bytes = [0; MESSAGE_LEN];
        let mut message = Message::new_checked(&mut bytes[..])
            .map_err(|e| ClientError::InvalidArgument(e.to_string()))?;
        message.set_command(chars);
        message.set_values(&values);
        message.set_index(index);
        let reply = self.exchange(&bytes, Expect { chars, index })?;
        let message = Message::new_checked(&reply[..])
            .map_err(|e| ClientError::InvalidArgument(e.to_string()))?;
        Ok(RawReply {
            chars: message.command(),
            values: message.values(),
            index: message.index(),
            bytes: reply,
        })
    }

    /// Removes and returns the queued unsolicited notices, oldest first.
    pub fn take_notices(&mut self) -> Vec<Text> {
        self.notices.drain(..).collect()
    }

    /// Reads every datagram already waiting on the socket without blocking, queueing the
    /// notices among them. Returns how many notices are queued.
    pub fn poll_notices(&mut self) -> Result<usize, ClientError> {
        self.socket.set_nonblocking(true)?;
        let result = self.drain_socket();
        self.socket.set_nonblocking(false)?;
        result?;
        Ok(self.notices.len())
    }

    /// How many notices were dropped because the queue was full.
    pub fn dropped_notices(&self) -> u64 {
        self.dropped_notices
    }

    /// How many normal replies arrived that answered no outstanding request (late answers to
    /// retried requests, typically).
    pub fn stale_replies(&self) -> u64 {
        self.stale_replies
    }

    fn drain_socket(&mut self) -> Result<(), ClientError> {
        let mut buf = [0; 2 * MESSAGE_LEN];
        loop {
            match self.socket.recv(&mut buf) {
                Ok(n) => {
                    if let Some(message) = self.verified(buf.get(..n).unwrap_or_default()) {
                        self.file(classify_unsolicited(&message));
                    }
                }
                Err(e) if e.kind() == ErrorKind::WouldBlock => return Ok(()),
                // An ICMP error left over from an earlier send.
                Err(e) if e.kind() == ErrorKind::ConnectionRefused => {}
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => return Err(e.into()),
            }
        }
    }

    /// Files a datagram that is not the awaited reply.
    fn file(&mut self, incoming: Incoming) {
        match incoming {
            Incoming::Notice(text) | Incoming::Rejected(text) => self.push_notice(text),
            Incoming::Reply | Incoming::Other => self.stale_replies += 1,
        }
    }

    fn push_notice(&mut self, text: Text) {
        if self.config.notice_capacity == 0 {
            self.dropped_notices += 1;
            return;
        }
        while self.notices.len() >= self.config.notice_capacity {
            self.notices.pop_front();
            self.dropped_notices += 1;
        }
        self.notices.push_back(text);
    }

    /// Sends `datagram` until the reply `expect` describes arrives, or the attempts run out.
    fn exchange(
        &mut self,
        datagram: &[u8; MESSAGE_LEN],
        expect: Expect,
    ) -> Result<[u8; MESSAGE_LEN], ClientError> {
        let identity = datagram.get(..2) == Some(&Command::Status.chars()[..])
            && datagram.get(MESSAGE_LEN - 1) == Some(&IDENTITY_INDEX);
        if !identity && self.signer.as_ref().is_some_and(Signer::needs_identity) {
            self.identify()?;
        }
        // Whatever arrived before this request cannot be its reply.
        self.poll_notices()?;
        let attempts = self.config.retries.saturating_add(1);
        // A controller that has just restarted drops signed requests other than stops for up
        // to RESERVE_AHEAD (docs/safety.md): with a key, resends go on for at least that long.
        let window = match self.signer {
            Some(_) => Duration::from_micros(RESERVE_AHEAD.saturating_mul(TIMESTAMP_UNIT_US)),
            None => Duration::ZERO,
        };
        let timeout_us = self.config.timeout.as_micros().max(1);
        let extra = u32::try_from(window.as_micros().div_ceil(timeout_us)).unwrap_or(u32::MAX);
        let started = Instant::now();
        let mut refused = false;
        let unverified = self.unverified;
        let mut sent = 0;
        // When the last send left: the resends end only after one sent `window` after the first.
        let mut last_sent = Duration::ZERO;
        for attempt in 0..attempts.saturating_add(extra).saturating_add(1) {
            let answered = self.unverified > unverified;
            if attempt >= attempts && (refused || answered || last_sent >= window) {
                break;
            }
            sent += 1;
            last_sent = started.elapsed();
            // Each attempt signed anew: the controller serves a timestamp once.
            let signed = self.signer.as_mut().map(|s| s.sign(datagram));
            let bytes = match &signed {
                Some((bytes, timestamp)) => {
                    if attempt == 0 {
                        self.signed_at = *timestamp;
                    }
                    &bytes[..]
                }
                None => &datagram[..],
            };
            match self.socket.send(bytes) {
                Ok(_) => {}
                Err(e) if e.kind() == ErrorKind::ConnectionRefused => {
                    refused = true;
                    continue;
                }
                Err(e) => return Err(e.into()),
            }
            match self.await_reply(expect)? {
                Awaited::Reply(reply) => return Ok(reply),
                Awaited::Refused => refused = true,
                Awaited::TimedOut => refused = false,
            }
        }
        let command = String::from_utf8_lossy(&expect.chars).into_owned();
        if refused {
            Err(ClientError::Refused(self.peer))
        } else if self.unverified > unverified {
            Err(ClientError::Unverified {
                command,
                count: self.unverified - unverified,
            })
        } else {
            Err(ClientError::Timeout {
                command,
                attempts: sent,
                timeout: self.config.timeout,
            })
        }
    }

    /// Waits up to the timeout for the reply to one send.
    fn await_reply(&mut self, expect: Expect) -> Result<Awaited, ClientError> {
        // None: a timeout beyond the clock's range, never reached.
        let deadline = Instant::now().checked_add(self.config.timeout);
        let mut buf = [0; 2 * MESSAGE_LEN];
        loop {
            let left = deadline.map_or(self.config.timeout, |deadline| {
                deadline.saturating_duration_since(Instant::now())
            });
            if left.is_zero() {
                return Ok(Awaited::TimedOut);
            }
            self.socket.set_read_timeout(Some(left))?;
            match self.socket.recv(&mut buf) {
                Ok(n) => {
                    let Some(datagram) = self.verified(buf.get(..n).unwrap_or_default()) else {
                        continue;
                    };
                    match expect.classify(&datagram) {
                        Incoming::Reply => {
                            let mut reply = [0; MESSAGE_LEN];
                            reply.iter_mut().zip(&datagram).for_each(|(r, b)| *r = *b);
                            return Ok(Awaited::Reply(reply));
                        }
                        Incoming::Rejected(text) => return Err(ClientError::Rejected(text)),
                        other => self.file(other),
                    }
                }
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {
                    return Ok(Awaited::TimedOut);
                }
                Err(e) if e.kind() == ErrorKind::ConnectionRefused => return Ok(Awaited::Refused),
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => return Err(e.into()),
            }
        }
    }
}

impl Client {
    /// The message of a datagram from the controller: as it is without a signer; with one,
    /// only if signed with the key and not older than the last request (else counted).
    fn verified(&mut self, datagram: &[u8]) -> Option<Vec<u8>> {
        let Some(signer) = &self.signer else {
            return Some(datagram.to_vec());
        };
        let message = signer.open(datagram, self.signed_at).map(|m| m.to_vec());
        if message.is_none() {
            self.unverified += 1;
        }
        message
    }
}

/// The outcome of waiting after one send.
enum Awaited {
    Reply([u8; MESSAGE_LEN]),
    TimedOut,
    Refused,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fake::{FakeController, text};
    use armgate_protocol::client::Command;

    fn fast() -> ClientConfig {
        ClientConfig {
            timeout: Duration::from_millis(40),
            retries: 3,
            notice_capacity: 8,
        }
    }

    /// For tests that expect an answer: long enough never to resend on a loaded machine.
    fn patient() -> ClientConfig {
        ClientConfig {
            timeout: Duration::from_secs(1),
            ..fast()
        }
    }

    /// `command` with all values zero and index 0.
    fn bare(command: Command) -> Request {
        Request {
            command,
            values: [0.0; VALUES],
            index: 0,
        }
    }

    /// A host without its port says what form the address takes.
    #[test]
    fn an_address_without_a_port_says_host_port() {
        let Err(ClientError::Address(why)) = Client::connect("127.0.0.1") else {
            panic!("127.0.0.1 without a port was taken");
        };
        assert!(why.contains("expected host:port"), "{why}");
    }

    #[test]
    fn normal_reply_is_returned() {
        let fake = FakeController::spawn(|request| {
            let mut reply = Reply::null(Command::Pose);
            reply.values = [0.5, 0.2, 0.1, 0.0, 0.0, 0.0, 1.0];
            assert_eq!(&request[..2], b"PS");
            vec![reply.to_bytes().to_vec()]
        });
        let mut client = Client::connect_with(fake.addr(), patient()).unwrap();
        let reply = client.request(bare(Command::Pose)).unwrap();
        assert_eq!(reply.command, Command::Pose);
        assert_eq!(reply.values, [0.5, 0.2, 0.1, 0.0, 0.0, 0.0, 1.0]);
        assert_eq!(fake.received().len(), 1);
        assert!(client.take_notices().is_empty());
        // A timeout beyond the clock's range waits as long as it takes, without an overflow.
        let endless = ClientConfig {
            timeout: Duration::MAX,
            ..patient()
        };
        let mut client = Client::connect_with(fake.addr(), endless).unwrap();
        assert_eq!(
            client.request(bare(Command::Pose)).unwrap().command,
            Command::Pose
        );
    }

    #[test]
    fn matching_error_text_is_a_rejection() {
        let fake = FakeController::spawn(|_| vec![text("ER20 Cmd BG rejected")]);
        let mut client = Client::connect_with(fake.addr(), patient()).unwrap();
        let err = client.request(bare(Command::Begin)).unwrap_err();
        match err {
            ClientError::Rejected(t) => assert_eq!(t.as_str(), "ER20 Cmd BG rejected"),
            other => panic!("{other:?}"),
        }
        // Rejections are not retried.
        assert_eq!(fake.received().len(), 1);
    }

    #[test]
    fn on_and_off_errors_are_rejections() {
        let fake = FakeController::spawn(|request| match &request[..2] {
            b"ON" => vec![text("ER11 Arm did not start")],
            _ => vec![text("ER10 Arm did not stop")],
        });
        let mut client = Client::connect_with(fake.addr(), patient()).unwrap();
        for (command, expected) in [
            (Command::On, "ER11 Arm did not start"),
            (Command::Off, "ER10 Arm did not stop"),
        ] {
            let err = client.request(bare(command));
            assert!(
                matches!(err, Err(ClientError::Rejected(t)) if t.as_str() == expected),
                "{err:?}"
            );
        }
    }

    #[test]
    fn unsolicited_notices_are_queued_and_skipped() {
        let fake = FakeController::spawn(|_| {
            vec![
                text("WN12 Joint limit."),
                text("ER21 Work space limit."),
                // A refusal of some other command, and a stale reply: neither is the answer.
                text("ER20 Cmd jB rejected"),
                Reply::null(Command::Stop).to_bytes().to_vec(),
                text("WN22 Inv Kin Divergence."),
                Reply::null(Command::Begin).to_bytes().to_vec(),
            ]
        });
        let mut client = Client::connect_with(fake.addr(), patient()).unwrap();
        let reply = client.request(bare(Command::Begin)).unwrap();
        assert_eq!(reply.command, Command::Begin);
        let notices: Vec<String> = client
            .take_notices()
            .iter()
            .map(|t| t.as_str().to_owned())
            .collect();
        assert_eq!(
            notices,
            [
                "WN12 Joint limit.",
                "ER21 Work space limit.",
                "ER20 Cmd jB rejected",
                "WN22 Inv Kin Divergence."
            ]
        );
        assert_eq!(client.stale_replies(), 1);
        assert!(client.take_notices().is_empty());
    }

    #[test]
    fn notice_queue_is_bounded_dropping_the_oldest() {
        let fake = FakeController::spawn(|_| {
            let mut out: Vec<Vec<u8>> = (0..5)
                .map(|k| text(&format!("ER3{k} Drive fault")))
                .collect();
            out.push(Reply::null(Command::Stop).to_bytes().to_vec());
            out
        });
        let mut config = patient();
        config.notice_capacity = 3;
        let mut client = Client::connect_with(fake.addr(), config).unwrap();
        client.request(bare(Command::Stop)).unwrap();
        let notices: Vec<String> = client
            .take_notices()
            .iter()
            .map(|t| t.as_str().to_owned())
            .collect();
        assert_eq!(
            notices,
            ["ER32 Drive fault", "ER33 Drive fault", "ER34 Drive fault"]
        );
        assert_eq!(client.dropped_notices(), 2);
    }

    #[test]
    fn timeout_resends_the_same_datagram() {
        let fake = FakeController::spawn(|_| vec![]);
        let mut client = Client::connect_with(fake.addr(), fast()).unwrap();
        let started = Instant::now();
        let err = client.request(bare(Command::Pose)).unwrap_err();
        match err {
            ClientError::Timeout {
                ref command,
                attempts,
                ..
            } => {
                assert_eq!(command, "PS");
                assert_eq!(attempts, 4);
            }
            ref other => panic!("{other:?}"),
        }
        assert_eq!(err.exit_code(), 2);
        assert!(started.elapsed() >= Duration::from_millis(4 * 40));
        let received = fake.wait_for(4);
        assert_eq!(received.len(), 4);
        assert!(
            received
                .iter()
                .all(|d| *d == bare(Command::Pose).to_bytes())
        );
    }

    #[test]
    fn a_retry_that_gets_an_answer_succeeds() {
        let mut seen = 0;
        let fake = FakeController::spawn(move |_| {
            seen += 1;
            if seen < 3 {
                vec![]
            } else {
                vec![Reply::null(Command::Pose).to_bytes().to_vec()]
            }
        });
        let mut client = Client::connect_with(
            fake.addr(),
            ClientConfig {
                timeout: Duration::from_millis(150),
                ..fast()
            },
        )
        .unwrap();
        client.request(bare(Command::Pose)).unwrap();
        assert_eq!(fake.received().len(), 3);
    }

    #[test]
    fn notices_before_a_request_are_not_taken_for_its_reply() {
        // The fake answers the first request twice: the second copy arrives before the next
        // request and must not be taken for its reply.
        let mut first = true;
        let fake = FakeController::spawn(move |_| {
            let reply = Reply::null(Command::Stop).to_bytes().to_vec();
            if std::mem::take(&mut first) {
                vec![reply.clone(), reply, text("WN27 Via point missed.")]
            } else {
                vec![]
            }
        });
        let mut client = Client::connect_with(fake.addr(), patient()).unwrap();
        let stop = bare(Command::Stop);
        client.request(stop).unwrap();
        std::thread::sleep(Duration::from_millis(50));
        let mut config = fast();
        config.retries = 0;
        client.config = config;
        assert!(matches!(
            client.request(stop),
            Err(ClientError::Timeout { attempts: 1, .. })
        ));
        assert_eq!(client.take_notices().len(), 1);
    }

    #[test]
    fn raw_requests_reach_unknown_commands() {
        let fake = FakeController::spawn(|request| {
            vec![text(&format!(
                "ER00 Cmd {} not understood",
                String::from_utf8_lossy(&request[..2])
            ))]
        });
        let mut client = Client::connect_with(fake.addr(), patient()).unwrap();
        let err = client.send_raw(*b"XY", [1.0; VALUES], 7).unwrap_err();
        assert!(
            matches!(err, ClientError::Rejected(t) if t.as_str() == "ER00 Cmd XY not understood")
        );
        let sent = fake.received();
        assert_eq!(&sent[0][..2], b"XY");
        assert_eq!(&sent[0][2..6], &1.0f32.to_le_bytes());
        assert_eq!(sent[0][30], 7);
    }

    #[test]
    fn a_closed_port_is_reported_as_refused() {
        let addr = {
            let probe = UdpSocket::bind("127.0.0.1:0").unwrap();
            probe.local_addr().unwrap()
        };
        let mut client = Client::connect_with(addr, fast()).unwrap();
        match client.request(bare(Command::Pose)) {
            Err(ClientError::Refused(a)) => assert_eq!(a, addr),
            // Some systems report no ICMP errors to UDP sockets.
            Err(ClientError::Timeout { .. }) => {}
            other => panic!("{other:?}"),
        }
    }
}
