//! The controller's fixed error and warning texts (spec §2.3, §2.5, §2.6): written here
//! ([`Notice::text`]) and read back ([`Notice::parse`], in `parse.rs`) from the same phrases.

mod parse;
#[cfg(test)]
mod samples;
#[cfg(test)]
mod table;

use core::fmt::{self, Write as _};

use super::header::{CMD, MSG};
use super::words::{Milli, phrase};

use super::{
    Command, DriveStatus, Error, Hit, Hold, JointBound, Lag, Rejection, Severity, Text,
    WorkspaceReason,
};

/// A fixed error or warning. Add a variant (with its [`code`](Self::code), severity and body) for
/// every new text, so that the codes stay in one place.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Notice {
    /// `ER00 Cmd XX not understood`: an unknown command pair.
    NotUnderstood([u8; 2]),
    /// `ER01 Msg XX undersized.`: a datagram shorter than 30 bytes.
    Undersized([u8; 2]),
    /// `ER10 Arm …`: `OF` refused, the drives being in this state (`already off`,
    /// `already stopping`, `stopped by fault`).
    ArmDidNotStop(DriveStatus),
    /// `ER11 Arm …`: `ON` refused, the drives being in this state (`already on`,
    /// `still stopping`).
    ArmDidNotStart(DriveStatus),
    /// `ER20 Cmd XX <reason>`: the request cannot be carried out now (e.g. `ER20 Cmd BG busy`).
    Rejected(Command, Rejection),
    /// `ER21 Work space limit.`
    WorkspaceLimit,
    /// `ER21 L3 hits B1`: the motion was stopped because a link of the arm, where it is
    /// commanded or where it would come to rest, came within the margin of a box, another
    /// link or the bounds (docs/safety.md).
    Collision(Hit),
    /// `WN12 Joint limit.`
    JointLimit,
    /// `WN22 Inv Kin Divergence.`
    IkDivergence,
    /// `ER23 Cmd XX bad number`: NaN/Inf, a zero quaternion, an invalid mode.
    BadNumber(Command),
    /// `ER24 Cmd XX bad index`: a via slot ≥ 20, or a joint bank the arm does not have.
    BadIndex(Command),
    /// `ER25 Cmd XX <reason>`: a Cartesian goal outside the workspace or out of reach.
    OutsideWorkspace(Command, WorkspaceReason),
    /// `ER26 Cmd XX jN < min` / `jN > max`: a joint goal, or the way to a Cartesian goal,
    /// beyond a joint limit.
    BeyondJointLimit(Command, JointBound),
    /// `WN27 Via point missed.`: a sequence stopped because a via point was not reached.
    ViaPointMissed,
    /// `ER40 Cmd XX by 192.168.1.2`: another client controls the arm while it moves (its IPv4
    /// address; `another client` for an IPv6 one, which may not fit).
    HeldBy(Command, Option<[u8; 4]>),
    /// `ER41 client silent 500 ms`: the controlling client said nothing for longer than its
    /// watchdog (`WD`, this many ms, at most 60,000) while the arm moved: the arm was stopped.
    ClientSilent(u16),
    /// `ER42 Cmd XX cancelled by ST`: a request that would start motion (a planning one, or
    /// a stream) waited for a later tick (the per-tick work budget, or behind its client's
    /// planning request) and was cancelled by a stop that arrived after it.
    Cancelled(Command),
    /// `WN12 jN at limit L` / `WN13 Held at workspace edge.` / `WN13 Held: L3 hits B1`: a
    /// stream holds the arm there.
    Held(Hold),
    /// `WN14 link 7 shared`: signed datagrams from two sources interleave on
    /// this link id; the older timestamps of each are dropped as replays (docs/protocol.md,
    /// "Signed datagrams").
    LinkShared(u8),
    /// `ER43 jN following error E`: joint N's measured position was E from its command, more
    /// than the robot file's `max_following_error`: the arm was stopped (stop cause 9).
    FollowingError(Lag),
    /// `ER44 Cmd KG branch past limits`: the pose is reached within the limits, but
    /// not in the configuration asked for.
    BranchBeyondLimits(Command),
}

impl Notice {
    /// Error or warning.
    pub const fn severity(self) -> Severity {
        match self {
            Self::JointLimit
            | Self::IkDivergence
            | Self::ViaPointMissed
            | Self::Held(_)
            | Self::LinkShared(_) => Severity::Warning,
            _ => Severity::Error,
        }
    }

    /// The two-digit code.
    pub const fn code(self) -> u8 {
        match self {
            Self::NotUnderstood(_) => 0,
            Self::Undersized(_) => 1,
            Self::ArmDidNotStop(_) => 10,
            Self::ArmDidNotStart(_) => 11,
            Self::Rejected(..) => 20,
            Self::WorkspaceLimit | Self::Collision(_) => 21,
            Self::JointLimit => 12,
            Self::IkDivergence => 22,
            Self::BadNumber(_) => 23,
            Self::BadIndex(_) => 24,
            Self::OutsideWorkspace(..) => 25,
            Self::BeyondJointLimit(..) => 26,
            Self::ViaPointMissed => 27,
            Self::HeldBy(..) => 40,
            Self::ClientSilent(_) => 41,
            Self::Cancelled(_) => 42,
            Self::FollowingError(_) => 43,
            Self::BranchBeyondLimits(_) => 44,
            Self::Held(Hold::JointLimit(_)) => 12,
            Self::Held(Hold::Workspace | Hold::Contact(_)) => 13,
            Self::LinkShared(_) => 14,
        }
    }

    /// The full text, e.g. `ER20 Cmd BG busy`.
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

/// The texts that are one fixed phrase.
const PHRASES: [(Notice, &str); 5] = [
    (Notice::WorkspaceLimit, "Work space limit."),
    (Notice::JointLimit, "Joint limit."),
    (Notice::IkDivergence, "Inv Kin Divergence."),
    (Notice::ViaPointMissed, "Via point missed."),
    (Notice::Held(Hold::Workspace), "Held at workspace edge."),
];

/// `ER10`'s phrase for each drive state (`Arm did not stop` read back as running).
const ARM_DID_NOT_STOP: [(DriveStatus, &str); 5] = [
    (DriveStatus::Off, "Arm already off"),
    (DriveStatus::Stopping, "Arm already stopping"),
    (DriveStatus::Faulted, "Arm stopped by fault"),
    (DriveStatus::Running, "Arm did not stop"),
    (DriveStatus::Starting, "Arm did not stop"),
];

/// `ER11`'s phrase for each drive state (`Arm did not start` read back as off).
const ARM_DID_NOT_START: [(DriveStatus, &str); 5] = [
    (DriveStatus::Running, "Arm already on"),
    (DriveStatus::Starting, "Arm already starting"),
    (DriveStatus::Stopping, "Arm still stopping"),
    (DriveStatus::Off, "Arm did not start"),
    (DriveStatus::Faulted, "Arm did not start"),
];

/// The words around the parts that vary.
const NOT_UNDERSTOOD: &str = "not understood";
const UNDERSIZED: &str = "undersized.";
const BAD_NUMBER: &str = "bad number";
const BAD_INDEX: &str = "bad index";
const BY: &str = "by ";
const ANOTHER_CLIENT: &str = "another client";
const CLIENT_SILENT: (&str, &str) = ("client silent ", " ms");
const CANCELLED: &str = "cancelled by ST";
const BRANCH_BEYOND_LIMITS: &str = "branch past limits";
const AT_LIMIT: &str = " at limit ";
const LINK_SHARED: (&str, &str) = ("link ", " shared");
const HELD: &str = "Held: ";

/// The text after the code.
struct Body(Notice);

impl fmt::Display for Body {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let cmd = |c: Command| Pair(c.chars());
        match self.0 {
            Notice::NotUnderstood(c) => write!(f, "{CMD} {} {NOT_UNDERSTOOD}", Pair(c)),
            Notice::Undersized(c) => write!(f, "{MSG} {} {UNDERSIZED}", Pair(c)),
            Notice::ArmDidNotStop(state) => {
                f.write_str(phrase(&ARM_DID_NOT_STOP, &state).unwrap_or_default())
            }
            Notice::ArmDidNotStart(state) => {
                f.write_str(phrase(&ARM_DID_NOT_START, &state).unwrap_or_default())
            }
            Notice::Rejected(c, why) => write!(f, "{CMD} {} {why}", cmd(c)),
            Notice::BadNumber(c) => write!(f, "{CMD} {} {BAD_NUMBER}", cmd(c)),
            Notice::BadIndex(c) => write!(f, "{CMD} {} {BAD_INDEX}", cmd(c)),
            Notice::OutsideWorkspace(c, why) => write!(f, "{CMD} {} {why}", cmd(c)),
            Notice::BeyondJointLimit(c, bound) => write!(f, "{CMD} {} {bound}", cmd(c)),
            // The octets one by one: `Ipv4Addr`'s Display has a panic path (its padding
            // buffer), which the control tick must not link.
            Notice::HeldBy(c, Some([a, b, x, y])) => {
                write!(f, "{CMD} {} {BY}{a}.{b}.{x}.{y}", cmd(c))
            }
            Notice::HeldBy(c, None) => write!(f, "{CMD} {} {BY}{ANOTHER_CLIENT}", cmd(c)),
            Notice::ClientSilent(ms) => write!(f, "{}{ms}{}", CLIENT_SILENT.0, CLIENT_SILENT.1),
            Notice::Cancelled(c) => write!(f, "{CMD} {} {CANCELLED}", cmd(c)),
            Notice::BranchBeyondLimits(c) => write!(f, "{CMD} {} {BRANCH_BEYOND_LIMITS}", cmd(c)),
            Notice::FollowingError(lag) => write!(f, "{lag}"),
            Notice::Collision(hit) => write!(f, "{hit}"),
            Notice::Held(Hold::JointLimit(bound)) => {
                write!(f, "j{}{AT_LIMIT}{}", bound.joint, Milli(bound.limit_milli))
            }
            Notice::Held(Hold::Contact(hit)) => write!(f, "{HELD}{hit}"),
            Notice::LinkShared(link) => write!(f, "{}{link}{}", LINK_SHARED.0, LINK_SHARED.1),
            fixed => f.write_str(phrase(&PHRASES, &fixed).unwrap_or_default()),
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
    use crate::client::PathPoint;

    #[test]
    fn the_holder_is_named_where_it_fits() {
        let held = |ip| Notice::HeldBy(Command::Begin, ip).text();
        assert_eq!(
            held(Some([192, 168, 100, 200])).as_str(),
            "ER40 Cmd BG by 192.168.100.200"
        );
        assert_eq!(held(None).as_str(), "ER40 Cmd BG by another client");
        assert_eq!(
            Notice::Cancelled(Command::ViaExecute).text().as_str(),
            "ER42 Cmd VE cancelled by ST"
        );
        assert_eq!(
            Notice::ClientSilent(60_000).text().as_str(),
            "ER41 client silent 60000 ms"
        );
    }

    #[test]
    fn texts_are_exact() {
        let cases = [
            (Notice::NotUnderstood(*b"XY"), "ER00 Cmd XY not understood"),
            (Notice::Undersized(*b"B?"), "ER01 Msg B? undersized."),
            (
                Notice::ArmDidNotStop(DriveStatus::Off),
                "ER10 Arm already off",
            ),
            (
                Notice::ArmDidNotStop(DriveStatus::Stopping),
                "ER10 Arm already stopping",
            ),
            (
                Notice::ArmDidNotStop(DriveStatus::Faulted),
                "ER10 Arm stopped by fault",
            ),
            (
                Notice::ArmDidNotStart(DriveStatus::Running),
                "ER11 Arm already on",
            ),
            (
                Notice::ArmDidNotStart(DriveStatus::Stopping),
                "ER11 Arm still stopping",
            ),
            (
                Notice::Rejected(Command::Begin, Rejection::Drives(DriveStatus::Starting)),
                "ER20 Cmd BG drives starting",
            ),
            (
                Notice::Rejected(Command::Begin, Rejection::Drives(DriveStatus::Off)),
                "ER20 Cmd BG drives off",
            ),
            (
                Notice::Rejected(Command::ViaExecute, Rejection::DriveFault(33)),
                "ER20 Cmd VE drive fault 33",
            ),
            (
                Notice::Rejected(Command::Recalibrate, Rejection::DrivesSettling),
                "ER20 Cmd RC drives settling",
            ),
            (
                Notice::Rejected(
                    Command::Recalibrate,
                    Rejection::NeedsMode(crate::client::Mode::Off),
                ),
                "ER20 Cmd RC needs mode 0",
            ),
            (
                Notice::Rejected(Command::JointVia, Rejection::Busy),
                "ER20 Cmd jV busy",
            ),
            (
                Notice::Rejected(Command::JointBegin, Rejection::NoGoal),
                "ER20 Cmd jB no goal",
            ),
            (
                Notice::Rejected(Command::JointExecute, Rejection::NoViaPoint),
                "ER20 Cmd jE no via point 0",
            ),
            (
                Notice::Rejected(Command::Pose, Rejection::NoMeasurement),
                "ER20 Cmd PS no measurement",
            ),
            (Notice::WorkspaceLimit, "ER21 Work space limit."),
            (
                Notice::Collision(Hit {
                    link: 5,
                    obstacle: crate::client::Obstacle::Link(2),
                }),
                "ER21 L5 hits L2",
            ),
            (
                Notice::OutsideWorkspace(
                    Command::JointBegin,
                    WorkspaceReason::Hits(
                        Hit {
                            link: 3,
                            obstacle: crate::client::Obstacle::Box(16),
                        },
                        PathPoint::Along(40),
                    ),
                ),
                "ER25 Cmd jB L3 hits B16 at 40%",
            ),
            (Notice::JointLimit, "WN12 Joint limit."),
            (Notice::IkDivergence, "WN22 Inv Kin Divergence."),
            (
                Notice::BadNumber(Command::GoalQuaternion),
                "ER23 Cmd GL bad number",
            ),
            (Notice::BadIndex(Command::ViaPoint), "ER24 Cmd VP bad index"),
            (
                Notice::OutsideWorkspace(Command::GoalRpy, WorkspaceReason::Goal),
                "ER25 Cmd GT outside workspace",
            ),
            (
                Notice::OutsideWorkspace(Command::Begin, WorkspaceReason::CrossesBox(40)),
                "ER25 Cmd BG crosses box at 40%",
            ),
            (
                Notice::OutsideWorkspace(
                    Command::Begin,
                    WorkspaceReason::Unreachable(PathPoint::Along(99)),
                ),
                "ER25 Cmd BG unreachable at 99%",
            ),
            (
                Notice::OutsideWorkspace(
                    Command::ViaExecute,
                    WorkspaceReason::Unreachable(PathPoint::Goal),
                ),
                "ER25 Cmd VE unreachable",
            ),
            (
                Notice::OutsideWorkspace(Command::Begin, WorkspaceReason::ArmOutside),
                "ER25 Cmd BG arm outside",
            ),
            (
                Notice::BeyondJointLimit(
                    Command::JointGoal,
                    JointBound::new(4, false, 0.785, PathPoint::Goal),
                ),
                "ER26 Cmd jG j5 < 0.785",
            ),
            (
                Notice::BeyondJointLimit(
                    Command::Begin,
                    JointBound::new(2, true, 1.6, PathPoint::Along(12)),
                ),
                "ER26 Cmd BG j3 > 1.600 at 12%",
            ),
            (Notice::ViaPointMissed, "WN27 Via point missed."),
            (
                Notice::Held(Hold::JointLimit(JointBound::new(
                    5,
                    true,
                    2.967,
                    PathPoint::Goal,
                ))),
                "WN12 j6 at limit 2.967",
            ),
            (
                Notice::Held(Hold::JointLimit(JointBound::new(
                    4,
                    false,
                    -1.745,
                    PathPoint::Goal,
                ))),
                "WN12 j5 at limit -1.745",
            ),
            (
                Notice::Held(Hold::Workspace),
                "WN13 Held at workspace edge.",
            ),
            (
                Notice::Held(Hold::Contact(Hit {
                    link: 3,
                    obstacle: crate::client::Obstacle::Box(1),
                })),
                "WN13 Held: L3 hits B1",
            ),
        ];
        for (notice, expected) in cases {
            assert!(expected.len() <= super::super::TEXT_CAPACITY, "{expected}");
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
