//! Why a datagram is not a request or reply.

use core::fmt;

/// Why a datagram is not a request or reply. Both cases carry bytes 0 and 1 as received, so
/// that the answer can name them (see [`Notice`](super::Notice)'s `From<Error>`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error {
    /// Shorter than [`MIN_LEN`](super::MIN_LEN) bytes. A byte the datagram lacks reads as `?`.
    Undersized([u8; 2]),
    /// Bytes 0 and 1 are not a known command pair.
    UnknownCommand([u8; 2]),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Undersized(c) => write!(f, "datagram {} undersized", c.escape_ascii()),
            Self::UnknownCommand(c) => write!(f, "unknown command {}", c.escape_ascii()),
        }
    }
}

impl core::error::Error for Error {}

/// Why a parsed message is not the value it is read as: a text, a report of `SQ`, a blend
/// tolerance.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DecodeError {
    /// Another command's message, or another `SQ` index.
    WrongCommand,
    /// A field that holds none of its values (a code, a whole count, a finite number).
    BadField,
}

impl fmt::Display for DecodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::WrongCommand => "another command's message",
            Self::BadField => "a field out of its range",
        })
    }
}

impl core::error::Error for DecodeError {}
