//! The client side of a tick: datagrams in, replies and notices out.

use core::net::{IpAddr, Ipv4Addr, SocketAddr};

use armgate_protocol::client::signed::SIGNED_LEN;

/// A shell's peer address, as the core knows its clients: a socket address. The one place
/// where a datagram's source enters the core (the command handler's session, and where
/// notices go).
pub trait Peer: Copy {
    /// The client's address.
    fn address(self) -> SocketAddr;
    /// The peer with this address (where a notice goes).
    fn from_address(address: SocketAddr) -> Self;
}

impl Peer for SocketAddr {
    fn address(self) -> SocketAddr {
        self
    }

    fn from_address(address: SocketAddr) -> Self {
        address
    }
}

/// One client without an address (recordings, benches, the fuzz target): every datagram is
/// from the unspecified address.
impl Peer for () {
    fn address(self) -> SocketAddr {
        SocketAddr::new(IpAddr::V4(Ipv4Addr::UNSPECIFIED), 0)
    }

    fn from_address(_: SocketAddr) -> Self {}
}

/// A client datagram (its first 44 bytes: a signed datagram's length; the protocol reads no
/// more) and the peer it came from or goes to. `P` is the shell's address type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Datagram<P> {
    bytes: [u8; SIGNED_LEN],
    /// How many of `bytes` are valid (≤ 44).
    len: u8,
    /// Source of a request, destination of a reply or notice.
    pub peer: P,
}

impl<P> Datagram<P> {
    /// The first (at most 44) bytes of `payload`, from or to `peer`.
    pub fn new(payload: &[u8], peer: P) -> Self {
        let mut bytes = [0; SIGNED_LEN];
        let mut len = 0u8;
        for (b, p) in bytes.iter_mut().zip(payload) {
            *b = *p;
            len += 1;
        }
        Self { bytes, len, peer }
    }

    /// The valid bytes.
    pub fn payload(&self) -> &[u8] {
        self.bytes.get(..usize::from(self.len)).unwrap_or_default()
    }
}

/// What an outgoing datagram is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outgoing {
    /// The answer to a request.
    Reply,
    /// An unsolicited warning or fault text.
    Notice,
}

/// The datagram could not be queued or sent (counted by the cycle).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Dropped;

/// The shell's datagram port: a UDP socket, the firmware's queues, a recording.
///
/// Both calls return at once. The shell checks its allow-list before a datagram is offered:
/// every request [`receive`](Self::receive) returns is handled.
pub trait Link<P> {
    /// The oldest request waiting, if any.
    fn receive(&mut self) -> Option<Datagram<P>>;
    /// Sends (or queues) `datagram` to its peer.
    fn send(&mut self, datagram: &Datagram<P>, kind: Outgoing) -> Result<(), Dropped>;
    /// Datagrams the shell dropped after [`send`](Self::send) accepted them (a destination
    /// that did not resolve), since it started; the cycle adds its own count of refused sends.
    fn dropped(&self) -> u64 {
        0
    }
}
