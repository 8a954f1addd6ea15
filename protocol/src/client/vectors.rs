//! Literal datagrams for the unit tests, written as their bytes: the encoder is checked against
//! them, never used to make them.

use super::{MESSAGE_LEN, Message, Request, VALUES};

/// A float field of 0.0.
pub const ZERO: [u8; 4] = [0; 4];

/// The datagram with command characters `chars`, the seven float fields' bytes `fields`
/// (little-endian, as sent) and the index byte `index`.
pub const fn datagram(chars: [u8; 2], fields: [[u8; 4]; VALUES], index: u8) -> [u8; MESSAGE_LEN] {
    let mut bytes = [0; MESSAGE_LEN];
    bytes[0] = chars[0];
    bytes[1] = chars[1];
    let mut field = 0;
    while field < VALUES {
        let mut byte = 0;
        while byte < 4 {
            bytes[2 + 4 * field + byte] = fields[field][byte];
            byte += 1;
        }
        field += 1;
    }
    bytes[MESSAGE_LEN - 1] = index;
    bytes
}

/// `bytes` parsed as a request; panics (fails the test) if they are not one.
pub fn request(bytes: &[u8]) -> Request {
    Message::new_checked(bytes)
        .and_then(|m| Request::parse(&m))
        .unwrap()
}
