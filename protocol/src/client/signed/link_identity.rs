//! How a signed client appears in the session's reports: link N is the address `0.0.0.N`,
//! port 0 (`0.0.0.0/8` is "this network", never a datagram's source). With a key the
//! controller knows a client by its link id, not its source address, so `SQ` index 3 and
//! `ER40 … by 0.0.0.N` name a signed holder this way; clients compare against it.

use core::net::{Ipv4Addr, SocketAddr};

/// The identity of signed link `link`: `0.0.0.<link>`, port 0.
pub fn link_identity(link: u8) -> SocketAddr {
    SocketAddr::from((Ipv4Addr::new(0, 0, 0, link), 0))
}

/// The link id whose identity `address` is, if it is one (link 0 is the controller's: the
/// unspecified address of a shell without addresses is none).
pub fn link_of_identity(address: SocketAddr) -> Option<u8> {
    match address {
        SocketAddr::V4(a) if a.port() == 0 => match a.ip().octets() {
            [0, 0, 0, link] if link != 0 => Some(link),
            _ => None,
        },
        _ => None,
    }
}
