//! The parts every `ER`/`WN` text shares, read back: severity, code, the command it names and
//! the detail after it (`ER20 Cmd BG busy` → error 20, `BG`, `busy`).
//!
//! These hold for any controller's texts, an older one's (`ER20 Cmd BG rejected`) and the drive
//! faults (`ER33 J4 PT buffer underflow`) included; [`Notice::parse`](super::Notice::parse)
//! reads this controller's texts down to their typed reasons.

use core::ops::RangeInclusive;

use super::words::decimal;
use super::{Command, DriveStatus, Lag, Notice, Severity, Text};

/// The codes of drive faults (`ER30`..`ER39`, docs/drives.md): formed above the drives, by the
/// core, from the fault. Each ends a running motion.
pub const DRIVE_FAULT_CODES: RangeInclusive<u8> = 30..=39;

/// Why a text is not one of this grammar's.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum NoticeError {
    /// Not `ER` or `WN`, two digits, then the end or a space.
    Malformed,
    /// A code the grammar does not define for this severity (a drive fault, or a newer
    /// controller's).
    UnknownCode,
    /// A known code, but none of its forms (an older controller's `ER20 Cmd BG rejected`).
    UnknownForm,
}

impl core::fmt::Display for NoticeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::Malformed => "not an ER/WN text with a two-digit code",
            Self::UnknownCode => "unknown code",
            Self::UnknownForm => "unknown form for its code",
        })
    }
}

impl core::error::Error for NoticeError {}

/// A text's shared parts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Header<'a> {
    /// `ER` or `WN`.
    pub severity: Severity,
    /// The two-digit code.
    pub code: u8,
    /// The characters a `Cmd XX` or `Msg XX` names, as received.
    pub command: Option<[u8; 2]>,
    /// What follows the command, or with none the whole text after the code.
    pub detail: &'a str,
}

impl<'a> Header<'a> {
    /// Splits `text` into its parts.
    pub fn parse(text: &'a Text) -> Result<Self, NoticeError> {
        let s = text.as_str();
        let digits = s.get(2..4).ok_or(NoticeError::Malformed)?;
        let code = decimal(digits).ok_or(NoticeError::Malformed)?;
        let body = match s.get(4..) {
            Some("") => "",
            Some(rest) => rest.strip_prefix(' ').ok_or(NoticeError::Malformed)?,
            None => return Err(NoticeError::Malformed),
        };
        let (command, detail) = match named(body, CMD).or_else(|| named(body, MSG)) {
            Some((chars, detail)) => (Some(chars), detail),
            None => (None, body),
        };
        Ok(Self {
            severity: text.severity(),
            code,
            command,
            detail,
        })
    }

    /// The request characters this text refuses, if it refuses one: the command it names, or
    /// `OF` for `ER10` and `ON` for `ER11`, which name none.
    pub fn refuses(&self) -> Option<[u8; 2]> {
        if self.severity != Severity::Error {
            return None;
        }
        let is = |notice: Notice| notice.code() == self.code;
        let fixed = [
            (Notice::ArmDidNotStop(DriveStatus::Off), Command::Off),
            (Notice::ArmDidNotStart(DriveStatus::Running), Command::On),
        ];
        fixed
            .into_iter()
            .find(|(notice, _)| is(*notice))
            .map(|(_, command)| command.chars())
            .or(self.command)
    }

    /// Whether a running motion will not complete: `ER21` (workspace limit), `WN22` (IK
    /// divergence), `WN27` (via point missed), `ER41` (the client watchdog stopped the arm),
    /// `ER43` (a following error stopped it) and the drive faults.
    pub fn ends_motion(&self) -> bool {
        const ENDING: [Notice; 5] = [
            Notice::WorkspaceLimit,
            Notice::IkDivergence,
            Notice::ViaPointMissed,
            Notice::ClientSilent(0),
            Notice::FollowingError(Lag {
                joint: 0,
                error_milli: 0,
            }),
        ];
        ENDING
            .iter()
            .any(|n| n.severity() == self.severity && n.code() == self.code)
            || self.is_drive_fault()
    }

    /// Whether this is a drive fault (`ER30`..`ER39`).
    pub fn is_drive_fault(&self) -> bool {
        self.severity == Severity::Error && DRIVE_FAULT_CODES.contains(&self.code)
    }
}

/// The words before the command characters a text names: `Cmd BG`, `Msg B?` (undersized).
pub(super) const CMD: &str = "Cmd";
pub(super) const MSG: &str = "Msg";

/// `word XX` at the start of `body` (then the end, or a space and the rest): the two
/// characters, and the rest.
pub(super) fn named<'a>(body: &'a str, word: &str) -> Option<([u8; 2], &'a str)> {
    let rest = body.strip_prefix(word)?.strip_prefix(' ')?;
    let chars = rest.as_bytes().get(..2)?;
    let after = rest.get(2..)?;
    let detail = match after {
        "" => "",
        _ => after.strip_prefix(' ')?,
    };
    Some(([*chars.first()?, *chars.get(1)?], detail))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::client::{MESSAGE_LEN, Message};

    /// Severity, code, named command and detail.
    type Parts = (Severity, u8, Option<[u8; 2]>, String);

    /// The text a datagram carries.
    fn text(s: &str) -> Text {
        let mut datagram = [0; MESSAGE_LEN];
        datagram[..s.len()].copy_from_slice(s.as_bytes());
        Text::parse(&Message::new_checked(&datagram[..]).unwrap()).unwrap()
    }

    fn parse(s: &str) -> Result<Parts, NoticeError> {
        Header::parse(&text(s)).map(|h| (h.severity, h.code, h.command, h.detail.to_owned()))
    }

    #[test]
    fn any_controllers_texts_split_into_their_parts() {
        use Severity::*;
        let cases = [
            ("ER20 Cmd BG busy", (Error, 20, Some(*b"BG"), "busy")),
            (
                "ER20 Cmd BG rejected",
                (Error, 20, Some(*b"BG"), "rejected"),
            ),
            (
                "ER01 Msg B? undersized.",
                (Error, 1, Some(*b"B?"), "undersized."),
            ),
            ("ER20 Cmd jB", (Error, 20, Some(*b"jB"), "")),
            (
                "ER33 J4 PT buffer underflow",
                (Error, 33, None, "J4 PT buffer underflow"),
            ),
            (
                "WN22 Inv Kin Divergence.",
                (Warning, 22, None, "Inv Kin Divergence."),
            ),
            ("ER21", (Error, 21, None, "")),
            ("ER20 Cmd BGx", (Error, 20, None, "Cmd BGx")),
        ];
        for (text, (severity, code, command, detail)) in cases {
            assert_eq!(
                parse(text),
                Ok((severity, code, command, detail.to_owned())),
                "{text}"
            );
        }
        for malformed in ["ER", "ER2", "ERx1 Cmd BG busy", "ER20Cmd", "WN-1 x"] {
            assert_eq!(parse(malformed), Err(NoticeError::Malformed), "{malformed}");
        }
    }

    #[test]
    fn refusals_name_their_request_and_some_notices_end_motions() {
        let header = |s: &str| {
            let text = text(s);
            let h = Header::parse(&text).unwrap();
            (h.refuses(), h.ends_motion())
        };
        assert_eq!(header("ER20 Cmd BG rejected"), (Some(*b"BG"), false));
        assert_eq!(header("ER10 Arm already off"), (Some(*b"OF"), false));
        assert_eq!(header("ER11 Arm already on"), (Some(*b"ON"), false));
        assert_eq!(header("ER41 client silent 500 ms"), (None, true));
        assert_eq!(header("ER21 Work space limit."), (None, true));
        assert_eq!(header("WN22 Inv Kin Divergence."), (None, true));
        assert_eq!(header("WN27 Via point missed."), (None, true));
        assert_eq!(header("ER30 J3 drive not answering"), (None, true));
        assert_eq!(header("ER39 J1 SDO abort 06020000"), (None, true));
        assert_eq!(header("WN39 J1 map 1A01:00 read back"), (None, false));
        assert_eq!(header("WN12 Joint limit."), (None, false));
        assert_eq!(header("WN20 Cmd BG busy"), (None, false));
    }
}
