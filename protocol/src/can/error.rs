//! Why bytes are not a valid frame or message.

use core::fmt;

/// Why bytes are not a valid frame, or a frame not the expected message.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error {
    /// The identifier does not fit in 11 bits.
    IdOutOfRange,
    /// More than 8 data bytes.
    TooLong,
    /// The COB-ID is not that of the expected message.
    WrongId,
    /// The data length is wrong for the message.
    WrongLength,
    /// A field holds a value the protocol does not define here: a mnemonic that is not two
    /// upper-case letters, a flag set where it has no meaning, an unknown NMT command or state,
    /// an unsupported SDO command specifier.
    Malformed,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::IdOutOfRange => "CAN identifier above 0x7FF",
            Self::TooLong => "more than 8 CAN data bytes",
            Self::WrongId => "unexpected COB-ID",
            Self::WrongLength => "wrong CAN data length",
            Self::Malformed => "malformed CAN message",
        })
    }
}

impl core::error::Error for Error {}
