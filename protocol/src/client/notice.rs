//! The controller's fixed error and warning texts (spec §2.3, §2.5, §2.6).

use core::fmt::{self, Write as _};

use super::{Command, Error, Severity, Text};

/// A fixed error or warning. Add a variant (with its [`code`](Self::code), severity and body) for
/// every new text, so that the codes stay in one place.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Notice {
    /// `ER00 Cmd XX not understood`: an unknown command pair.
    NotUnderstood([u8; 2]),
    /// `ER01 Msg XX undersized.`: a datagram shorter than 30 bytes.
    Undersized([u8; 2]),
    /// `ER10 Arm did not stop`.
    ArmDidNotStop,
    /// `ER11 Arm did not start`.
    ArmDidNotStart,
    /// `ER20 Cmd XX rejected`.
    Rejected(Command),
    /// `ER21 Work space limit.`
    WorkspaceLimit,
    /// `WN12 Joint limit.`
    JointLimit,
    /// `WN22 Inv Kin Divergence.`
    IkDivergence,
    /// `ER23 Cmd XX bad number`: NaN/Inf, a zero quaternion, an invalid mode.
    BadNumber(Command),
    /// `ER24 Cmd XX bad index`: a via slot ≥ 20, or a joint bank the arm does not have.
    BadIndex(Command),
    /// `ER25 Cmd XX outside workspace`: a goal outside the bounds or inside an exclusion box.
    OutsideWorkspace(Command),
    /// `ER26 Cmd XX beyond joint limit`: a joint goal outside the joint limits.
    BeyondJointLimit(Command),
    /// `WN27 Via point missed.`: a sequence stopped because a via point was not reached.
    ViaPointMissed,
}

impl Notice {
    /// Error or warning.
    pub const fn severity(self) -> Severity {
        match self {
            Self::JointLimit | Self::IkDivergence | Self::ViaPointMissed => Severity::Warning,
            _ => Severity::Error,
        }
    }

    /// The two-digit code.
    pub const fn code(self) -> u8 {
        match self {
            Self::NotUnderstood(_) => 0,
            Self::Undersized(_) => 1,
            Self::ArmDidNotStop => 10,
            Self::ArmDidNotStart => 11,
            Self::Rejected(_) => 20,
            Self::WorkspaceLimit => 21,
            Self::JointLimit => 12,
            Self::IkDivergence => 22,
            Self::BadNumber(_) => 23,
            Self::BadIndex(_) => 24,
            Self::OutsideWorkspace(_) => 25,
            Self::BeyondJointLimit(_) => 26,
            Self::ViaPointMissed => 27,
        }
    }

    /// The full text, e.g. `ER20 Cmd BG rejected`.
    pub fn text(self) -> Text {
        Text::new(self.severity(), self.code(), Body(self))
    }
}

impl From<Error> for Notice {
    fn from(error: Error) -> Self {
        match error {
            Error::Undersized(chars) => Self::Undersized(chars),
            Error::UnknownCommand(chars) => Self::NotUnderstood(chars),
        }
    }
}

impl fmt::Display for Notice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.text().fmt(f)
    }
}

/// The text after the code.
struct Body(Notice);

impl fmt::Display for Body {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Notice::NotUnderstood(c) => write!(f, "Cmd {} not understood", Pair(c)),
            Notice::Undersized(c) => write!(f, "Msg {} undersized.", Pair(c)),
            Notice::ArmDidNotStop => f.write_str("Arm did not stop"),
            Notice::ArmDidNotStart => f.write_str("Arm did not start"),
            Notice::Rejected(command) => write!(f, "Cmd {} rejected", Pair(command.chars())),
            Notice::WorkspaceLimit => f.write_str("Work space limit."),
            Notice::JointLimit => f.write_str("Joint limit."),
            Notice::IkDivergence => f.write_str("Inv Kin Divergence."),
            Notice::BadNumber(c) => write!(f, "Cmd {} bad number", Pair(c.chars())),
            Notice::BadIndex(c) => write!(f, "Cmd {} bad index", Pair(c.chars())),
            Notice::OutsideWorkspace(c) => write!(f, "Cmd {} outside workspace", Pair(c.chars())),
            Notice::BeyondJointLimit(c) => write!(f, "Cmd {} beyond joint limit", Pair(c.chars())),
            Notice::ViaPointMissed => f.write_str("Via point missed."),
        }
    }
}

/// Two command characters, as received ([`Text`] sanitises them).
struct Pair([u8; 2]);

impl fmt::Display for Pair {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.iter().try_for_each(|&b| f.write_char(char::from(b)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texts_are_exact() {
        let cases = [
            (Notice::NotUnderstood(*b"XY"), "ER00 Cmd XY not understood"),
            (Notice::Undersized(*b"B?"), "ER01 Msg B? undersized."),
            (Notice::ArmDidNotStop, "ER10 Arm did not stop"),
            (Notice::ArmDidNotStart, "ER11 Arm did not start"),
            (Notice::Rejected(Command::JointVia), "ER20 Cmd jV rejected"),
            (Notice::WorkspaceLimit, "ER21 Work space limit."),
            (Notice::JointLimit, "WN12 Joint limit."),
            (Notice::IkDivergence, "WN22 Inv Kin Divergence."),
            (
                Notice::BadNumber(Command::GoalQuaternion),
                "ER23 Cmd GL bad number",
            ),
            (Notice::BadIndex(Command::ViaPoint), "ER24 Cmd VP bad index"),
            (
                Notice::OutsideWorkspace(Command::GoalRpy),
                "ER25 Cmd GT outside workspace",
            ),
            (
                Notice::BeyondJointLimit(Command::JointGoal),
                "ER26 Cmd jG beyond joint limit",
            ),
            (Notice::ViaPointMissed, "WN27 Via point missed."),
        ];
        for (notice, expected) in cases {
            assert_eq!(notice.text().as_str(), expected);
            assert_eq!(notice.to_string(), expected);
        }
    }

    #[test]
    fn non_printable_command_bytes_become_question_marks() {
        assert_eq!(
            Notice::NotUnderstood([0, 0xFF]).text().as_str(),
            "ER00 Cmd ?? not understood"
        );
    }

    #[test]
    fn errors_map_to_their_notices() {
        assert_eq!(
            Notice::from(Error::Undersized(*b"BG")),
            Notice::Undersized(*b"BG")
        );
        assert_eq!(
            Notice::from(Error::UnknownCommand(*b"xx")),
            Notice::NotUnderstood(*b"xx")
        );
    }
}
