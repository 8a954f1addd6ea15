//! Error and warning texts (`ER…`, `WN…`).

use core::fmt::{self, Write as _};

use super::{DecodeError, MESSAGE_LEN, Message};

/// The most characters a text holds; byte 30 always stays NUL.
pub const TEXT_CAPACITY: usize = MESSAGE_LEN - 1;

/// Whether a text reports an error or a warning.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Severity {
    /// `ER`.
    Error,
    /// `WN`.
    Warning,
}

impl Severity {
    /// The two characters that start the text.
    pub const fn prefix(self) -> &'static str {
        match self {
            Self::Error => "ER",
            Self::Warning => "WN",
        }
    }

    /// The severity whose prefix these characters are.
    pub fn from_prefix(chars: [u8; 2]) -> Option<Self> {
        [Self::Error, Self::Warning]
            .into_iter()
            .find(|s| s.prefix().as_bytes() == chars)
    }
}

/// An error or warning text: printable ASCII from byte 0, NUL-terminated, zero-filled to
/// [`MESSAGE_LEN`] bytes (the seed left stale bytes after the NUL; this does not).
///
/// Characters past [`TEXT_CAPACITY`] are dropped. Anything but printable ASCII (including a NUL,
/// which would end the text early) becomes `?`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Text {
    severity: Severity,
    len: u8,
    bytes: [u8; MESSAGE_LEN],
}

impl Text {
    /// `ER` or `WN`, `code` as two decimal digits (keep it below 100), a space, then `body`:
    /// `Text::new(Severity::Error, 20, "Cmd BG rejected")` is `ER20 Cmd BG rejected`.
    pub fn new(severity: Severity, code: u8, body: impl fmt::Display) -> Self {
        let mut text = Builder::new(severity);
        // A `Builder` never fails, and if `body` does, the text keeps what it wrote.
        let _ = write!(text, "{}{code:02} {body}", severity.prefix());
        text.0
    }

    /// The text in a received message, if it starts with `ER` or `WN`: the bytes up to the first
    /// NUL, at most [`TEXT_CAPACITY`] of them.
    pub fn parse<T: AsRef<[u8]>>(message: &Message<T>) -> Result<Self, DecodeError> {
        let severity = Severity::from_prefix(message.command()).ok_or(DecodeError::WrongCommand)?;
        let mut text = Builder::new(severity);
        message
            .bytes()
            .into_iter()
            .take_while(|&b| b != 0)
            .for_each(|b| text.push(char::from(b)));
        Ok(text.0)
    }

    /// Error or warning.
    pub const fn severity(&self) -> Severity {
        self.severity
    }

    /// The text, without the NUL.
    pub fn as_str(&self) -> &str {
        let bytes = self.bytes.get(..usize::from(self.len)).unwrap_or_default();
        core::str::from_utf8(bytes).unwrap_or_default()
    }

    /// Writes the text into `message`, zero-filling the rest.
    pub fn emit<T: AsRef<[u8]> + AsMut<[u8]>>(&self, message: &mut Message<T>) {
        message.set_bytes(&self.bytes);
    }

    /// The text as a datagram.
    pub const fn to_bytes(&self) -> [u8; MESSAGE_LEN] {
        self.bytes
    }
}

impl fmt::Display for Text {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

#[cfg(feature = "defmt")]
impl defmt::Format for Text {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(f, "{=str}", self.as_str());
    }
}

/// Appends to a text, sanitising and truncating.
struct Builder(Text);

impl Builder {
    const fn new(severity: Severity) -> Self {
        Self(Text {
            severity,
            len: 0,
            bytes: [0; MESSAGE_LEN],
        })
    }

    fn push(&mut self, c: char) {
        let byte = if c == ' ' || c.is_ascii_graphic() {
            c as u8
        } else {
            b'?'
        };
        let len = usize::from(self.0.len);
        if len < TEXT_CAPACITY
            && let Some(slot) = self.0.bytes.get_mut(len)
        {
            *slot = byte;
            self.0.len += 1;
        }
    }
}

impl fmt::Write for Builder {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        s.chars().for_each(|c| self.push(c));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_code_and_body() {
        let text = Text::new(Severity::Warning, 7, format_args!("f{} bad", 3));
        assert_eq!(text.as_str(), "WN07 f3 bad");
        assert_eq!(text.severity(), Severity::Warning);
    }

    #[test]
    fn truncates_to_capacity_and_keeps_the_nul() {
        let text = Text::new(Severity::Error, 99, "0123456789".repeat(4));
        assert_eq!(text.as_str(), "ER99 0123456789012345678901234");
        assert_eq!(text.as_str().len(), TEXT_CAPACITY);
        assert_eq!(text.to_bytes()[30], 0);
    }

    #[test]
    fn sanitises_non_printable() {
        let text = Text::new(Severity::Error, 1, "a\0b\u{e9}\n");
        assert_eq!(text.as_str(), "ER01 a?b??");
    }

    #[test]
    fn parse_reads_up_to_the_nul_only_for_er_and_wn() {
        let mut bytes = *b"WN12 Joint limit.\0stale bytes!!";
        let message = Message::new_checked(&bytes[..]).unwrap();
        let text = Text::parse(&message).unwrap();
        assert_eq!(text.as_str(), "WN12 Joint limit.");
        assert_eq!(text.severity(), Severity::Warning);
        bytes[..2].copy_from_slice(b"GB");
        assert_eq!(
            Text::parse(&Message::new_checked(&bytes[..]).unwrap()),
            Err(DecodeError::WrongCommand)
        );
    }

    #[test]
    fn parse_without_nul_stops_at_capacity() {
        let mut bytes = [b'x'; 32];
        bytes[..2].copy_from_slice(b"ER");
        let text = Text::parse(&Message::new_checked(&bytes[..]).unwrap()).unwrap();
        assert_eq!(text.as_str().len(), TEXT_CAPACITY);
        assert!(text.as_str().ends_with('x'));
    }
}
