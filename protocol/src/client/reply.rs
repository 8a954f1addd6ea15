//! A normal reply: the request's characters reversed, seven floats, index.

use super::message::datagram;
use super::{Command, Error, MESSAGE_LEN, Message, VALUES};

/// A normal reply, sent with the command's characters reversed (`BG` → `GB`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Reply {
    /// The command answered.
    pub command: Command,
    /// f0..f6.
    pub values: [f32; VALUES],
    /// The index byte.
    pub index: u8,
}

impl Reply {
    /// The "null reply": all values zero, index 0.
    pub const fn null(command: Command) -> Self {
        Self {
            command,
            values: [0.0; VALUES],
            index: 0,
        }
    }

    /// Decodes a reply (on the client side). A text is not a reply: try
    /// [`Text::parse`](super::Text::parse) first.
    pub fn parse<T: AsRef<[u8]>>(message: &Message<T>) -> Result<Self, Error> {
        let (command, values, index) = message.decode(Command::from_reply_chars)?;
        Ok(Self {
            command,
            values,
            index,
        })
    }

    /// Writes the reply into `message`.
    pub fn emit<T: AsRef<[u8]> + AsMut<[u8]>>(&self, message: &mut Message<T>) {
        message.encode(self.command.reply_chars(), &self.values, self.index);
    }

    /// The reply as a datagram.
    pub fn to_bytes(&self) -> [u8; MESSAGE_LEN] {
        datagram(|message| self.emit(message))
    }
}
