//! A client request: command, seven floats, index.

use super::message::datagram;
use super::{Command, Error, MESSAGE_LEN, Message, VALUES};

/// A decoded request. The floats are kept as received (NaN included): judging them is the
/// core's job, not the wire's.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Request {
    /// The command.
    pub command: Command,
    /// f0..f6; fields the command does not use are ignored (send them as 0).
    pub values: [f32; VALUES],
    /// The index byte (the via point for `jV` and `VP`).
    pub index: u8,
}

impl Request {
    /// Decodes a request; an unknown pair is [`Error::UnknownCommand`].
    pub fn parse<T: AsRef<[u8]>>(message: &Message<T>) -> Result<Self, Error> {
        let (command, values, index) = message.decode(Command::from_chars)?;
        Ok(Self {
            command,
            values,
            index,
        })
    }

    /// Writes the request into `message`.
    pub fn emit<T: AsRef<[u8]> + AsMut<[u8]>>(&self, message: &mut Message<T>) {
        message.encode(self.command.chars(), &self.values, self.index);
    }

    /// The request as a datagram.
    pub fn to_bytes(&self) -> [u8; MESSAGE_LEN] {
        datagram(|message| self.emit(message))
    }
}
