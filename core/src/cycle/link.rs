//! The client side of a tick: datagrams in, replies and notices out.

use armgate_protocol::client::signed::SIGNED_LEN;

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
}
