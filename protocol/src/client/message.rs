//! The length-checked view of one client datagram.

use super::{Command, Error};

/// The length of every message the controller sends, and the most it reads of a datagram.
pub const MESSAGE_LEN: usize = 31;

/// The shortest datagram accepted: a missing index byte (30 bytes) is read as index 0.
pub const MIN_LEN: usize = 30;

/// The number of float fields, f0..f6.
pub const VALUES: usize = 7;

/// Byte offsets of the fields.
mod field {
    pub const COMMAND: usize = 0;
    pub const VALUES: usize = 2;
    pub const INDEX: usize = 30;
}

/// A client datagram of at least [`MIN_LEN`] bytes.
///
/// Only the first [`MESSAGE_LEN`] bytes are ever read or written: a longer datagram is treated as
/// truncated to 31 bytes, as the seed's 31-byte receive did. Emit into a buffer of exactly
/// [`MESSAGE_LEN`] bytes; in a 30-byte buffer the index is not written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Message<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> Message<T> {
    /// Wraps a datagram, refusing one shorter than [`MIN_LEN`] bytes.
    ///
    /// The [`Error::Undersized`] error carries bytes 0 and 1, with `?` standing for a byte the
    /// datagram does not have, so that the answer `ER01 Msg XX undersized.` never shows stale
    /// or invented data.
    pub fn new_checked(buffer: T) -> Result<Self, Error> {
        let bytes = buffer.as_ref();
        if bytes.len() < MIN_LEN {
            let char_at = |i| bytes.get(i).copied().unwrap_or(b'?');
            return Err(Error::Undersized([char_at(0), char_at(1)]));
        }
        Ok(Self { buffer })
    }

    /// The underlying buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// Bytes 0 and 1: the command characters (or the first two characters of a text).
    pub fn command(&self) -> [u8; 2] {
        self.read(field::COMMAND)
    }

    /// f0..f6, decoded from little-endian binary32.
    pub fn values(&self) -> [f32; VALUES] {
        core::array::from_fn(|n| f32::from_le_bytes(self.read(field::VALUES + 4 * n)))
    }

    /// Byte 30, the index; 0 for a 30-byte datagram.
    pub fn index(&self) -> u8 {
        let [index] = self.read(field::INDEX);
        index
    }

    /// The first [`MESSAGE_LEN`] bytes, zero past the end of a shorter buffer.
    pub fn bytes(&self) -> [u8; MESSAGE_LEN] {
        self.read(0)
    }

    /// The command (looked up in `lookup`), the values and the index: the shared layout of
    /// requests and replies.
    pub(super) fn decode(
        &self,
        lookup: fn([u8; 2]) -> Option<Command>,
    ) -> Result<(Command, [f32; VALUES], u8), Error> {
        let chars = self.command();
        let command = lookup(chars).ok_or(Error::UnknownCommand(chars))?;
        Ok((command, self.values(), self.index()))
    }

    /// `N` bytes from `offset`; bytes past the end of the buffer read as zero.
    fn read<const N: usize>(&self, offset: usize) -> [u8; N] {
        let mut out = [0; N];
        let bytes = self.buffer.as_ref().get(offset..).unwrap_or_default();
        out.iter_mut().zip(bytes).for_each(|(o, b)| *o = *b);
        out
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> Message<T> {
    /// Sets bytes 0 and 1.
    pub fn set_command(&mut self, chars: [u8; 2]) {
        self.write(field::COMMAND, &chars);
    }

    /// Sets f0..f6, as little-endian binary32.
    pub fn set_values(&mut self, values: &[f32; VALUES]) {
        for (n, value) in values.iter().enumerate() {
            self.write(field::VALUES + 4 * n, &value.to_le_bytes());
        }
    }

    /// Sets byte 30, the index.
    pub fn set_index(&mut self, index: u8) {
        self.write(field::INDEX, &[index]);
    }

    /// Sets all [`MESSAGE_LEN`] bytes.
    pub fn set_bytes(&mut self, bytes: &[u8; MESSAGE_LEN]) {
        self.write(0, bytes);
    }

    /// Writes the shared layout of requests and replies.
    pub(super) fn encode(&mut self, chars: [u8; 2], values: &[f32; VALUES], index: u8) {
        self.set_command(chars);
        self.set_values(values);
        self.set_index(index);
    }

    /// Copies `bytes` to `offset`, dropping whatever lies past the end of the buffer.
    fn write(&mut self, offset: usize, bytes: &[u8]) {
        let buffer = self.buffer.as_mut().get_mut(offset..).unwrap_or_default();
        buffer.iter_mut().zip(bytes).for_each(|(o, b)| *o = *b);
    }
}

/// A zeroed datagram, filled by `emit`.
pub(super) fn datagram(emit: impl FnOnce(&mut Message<&mut [u8]>)) -> [u8; MESSAGE_LEN] {
    let mut bytes = [0; MESSAGE_LEN];
    emit(&mut Message {
        buffer: &mut bytes[..],
    });
    bytes
}
