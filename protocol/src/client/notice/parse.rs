//! Reading a text back into its [`Notice`], from the phrases the text was written with.

use core::net::Ipv4Addr;

use super::super::header::{Header, named};
use super::super::words::{Milli, decimal, value_of};
use super::*;
use crate::client::NoticeError;

impl Notice {
    /// The notice `text` is: `ER20 Cmd BG busy` → `Rejected(Begin, Busy)`.
    ///
    /// A few texts stand for several values and read back as one of them: `Arm did not stop`
    /// as running, `Arm did not start` as off, and `WN12 jN at limit L`, which does not say
    /// which side, as the minimum.
    pub fn parse(text: &Text) -> Result<Self, NoticeError> {
        let header = Header::parse(text)?;
        let (severity, code) = (header.severity, header.code);
        let body = text.as_str().get(5..).unwrap_or_default();
        if let Some(fixed) = PHRASES
            .iter()
            .find(|(n, p)| *p == body && n.code() == code && n.severity() == severity)
        {
            return Ok(fixed.0);
        }
        // The command named by `Cmd XX`, if it is one, and what follows.
        let command = || {
            let (chars, detail) = named(body, CMD)?;
            Some((Command::from_chars(chars)?, detail))
        };
        let with = |detail: &str, notice: fn(Command) -> Self| {
            command()
                .filter(|(_, d)| *d == detail)
                .map(|(c, _)| notice(c))
        };
        let parsed = match (severity, code) {
            (Severity::Error, 0) => named(body, CMD)
                .filter(|(_, d)| *d == NOT_UNDERSTOOD)
                .map(|(c, _)| Self::NotUnderstood(c)),
            (Severity::Error, 1) => named(body, MSG)
                .filter(|(_, d)| *d == UNDERSIZED)
                .map(|(c, _)| Self::Undersized(c)),
            (Severity::Error, 10) => value_of(&ARM_DID_NOT_STOP, body).map(Self::ArmDidNotStop),
            (Severity::Error, 11) => value_of(&ARM_DID_NOT_START, body).map(Self::ArmDidNotStart),
            (Severity::Error, 20) => {
                command().and_then(|(c, d)| Some(Self::Rejected(c, Rejection::parse(d)?)))
            }
            (Severity::Error, 23) => with(BAD_NUMBER, Self::BadNumber),
            (Severity::Error, 24) => with(BAD_INDEX, Self::BadIndex),
            (Severity::Error, 25) => command()
                .and_then(|(c, d)| Some(Self::OutsideWorkspace(c, WorkspaceReason::parse(d)?))),
            (Severity::Error, 26) => {
                command().and_then(|(c, d)| Some(Self::BeyondJointLimit(c, JointBound::parse(d)?)))
            }
            (Severity::Error, 40) => command().and_then(|(c, d)| {
                let holder = match d.strip_prefix(BY)? {
                    ANOTHER_CLIENT => None,
                    ip => Some(ip.parse::<Ipv4Addr>().ok()?.octets()),
                };
                Some(Self::HeldBy(c, holder))
            }),
            (Severity::Error, 41) => body
                .strip_prefix(CLIENT_SILENT.0)
                .and_then(|rest| rest.strip_suffix(CLIENT_SILENT.1))
                .and_then(decimal)
                .map(Self::ClientSilent),
            (Severity::Error, 42) => with(CANCELLED, Self::Cancelled),
            (Severity::Error, 43) => Lag::parse(body).map(Self::FollowingError),
            (Severity::Error, 44) => with(BRANCH_BEYOND_LIMITS, Self::BranchBeyondLimits),
            (Severity::Warning, 12) => held_at_limit(body),
            (Severity::Warning, 14) => body
                .strip_prefix(LINK_SHARED.0)
                .and_then(|rest| rest.strip_suffix(LINK_SHARED.1))
                .and_then(decimal)
                .map(Self::LinkShared),
            (Severity::Error, 21) => super::super::Hit::parse(body).map(Self::Collision),
            (Severity::Warning, 13) => body
                .strip_prefix(HELD)
                .and_then(super::super::Hit::parse)
                .map(|hit| Self::Held(Hold::Contact(hit))),
            // The fixed phrases, matched above.
            (Severity::Warning, 22 | 27) => None,
            _ => return Err(NoticeError::UnknownCode),
        };
        parsed.ok_or(NoticeError::UnknownForm)
    }
}

/// `jN at limit L`.
fn held_at_limit(body: &str) -> Option<Notice> {
    let (joint, limit) = body.strip_prefix('j')?.split_once(AT_LIMIT)?;
    Some(Notice::Held(Hold::JointLimit(JointBound {
        joint: decimal(joint)?,
        above_max: false,
        limit_milli: Milli::parse(limit)?.0,
        at: super::super::PathPoint::Goal,
    })))
}

#[cfg(test)]
mod tests {
    use super::super::samples::samples;
    use super::*;
    use crate::client::{MESSAGE_LEN, Message, Mode, PathPoint};

    /// The text a datagram carries.
    fn received(bytes: &[u8]) -> Text {
        let mut datagram = [0; MESSAGE_LEN];
        datagram[..bytes.len()].copy_from_slice(bytes);
        Text::parse(&Message::new_checked(&datagram[..]).unwrap()).unwrap()
    }

    /// The value a text reads back as, where the text stands for several.
    fn canonical(notice: Notice) -> Notice {
        match notice {
            Notice::ArmDidNotStop(DriveStatus::Starting) => {
                Notice::ArmDidNotStop(DriveStatus::Running)
            }
            Notice::ArmDidNotStart(DriveStatus::Faulted) => {
                Notice::ArmDidNotStart(DriveStatus::Off)
            }
            Notice::Held(Hold::JointLimit(bound)) => Notice::Held(Hold::JointLimit(JointBound {
                above_max: false,
                ..bound
            })),
            other => other,
        }
    }

    #[test]
    fn every_variant_reads_back() {
        let mut count = 0;
        for notice in samples() {
            let text = notice.text();
            assert!(
                text.as_str().len() <= crate::client::TEXT_CAPACITY,
                "{text}"
            );
            let parsed = Notice::parse(&received(&text.to_bytes()));
            assert_eq!(parsed, Ok(canonical(notice)), "{text}");
            count += 1;
        }
        assert!(count > 40);
    }

    #[test]
    fn literal_datagrams_read_as_their_notices() {
        let cases: [(&[u8], Notice); 10] = [
            (
                b"ER20 Cmd BG busy\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0",
                Notice::Rejected(Command::Begin, Rejection::Busy),
            ),
            (
                b"ER20 Cmd RC needs mode 0",
                Notice::Rejected(Command::Recalibrate, Rejection::NeedsMode(Mode::Off)),
            ),
            (
                b"ER20 Cmd VE drive fault 05",
                Notice::Rejected(Command::ViaExecute, Rejection::DriveFault(5)),
            ),
            (
                b"ER26 Cmd BG j3 > 1.600 at 12%",
                Notice::BeyondJointLimit(
                    Command::Begin,
                    JointBound {
                        joint: 3,
                        above_max: true,
                        limit_milli: 1600,
                        at: PathPoint::Along(12),
                    },
                ),
            ),
            (
                b"ER25 Cmd GT outside workspace",
                Notice::OutsideWorkspace(Command::GoalRpy, WorkspaceReason::Goal),
            ),
            (
                b"ER40 Cmd BG by 10.0.0.7",
                Notice::HeldBy(Command::Begin, Some([10, 0, 0, 7])),
            ),
            (b"ER41 client silent 500 ms", Notice::ClientSilent(500)),
            (b"WN14 link 7 shared", Notice::LinkShared(7)),
            (b"ER01 Msg B? undersized.", Notice::Undersized(*b"B?")),
            (
                b"WN12 j5 at limit -1.745",
                Notice::Held(Hold::JointLimit(JointBound {
                    joint: 5,
                    above_max: false,
                    limit_milli: -1745,
                    at: PathPoint::Goal,
                })),
            ),
        ];
        for (bytes, notice) in cases {
            let text = received(bytes);
            assert_eq!(Notice::parse(&text), Ok(notice), "{text}");
            let mut written = [0; MESSAGE_LEN];
            written[..bytes.len()].copy_from_slice(bytes);
            assert_eq!(notice.text().to_bytes(), written, "{text}");
        }
    }

    #[test]
    fn other_texts_say_why_they_are_not_notices() {
        let cases: [(NoticeError, &[&[u8]]); 3] = [
            (
                NoticeError::UnknownForm,
                &[
                    b"ER20 Cmd BG rejected",
                    b"ER10 Arm maybe",
                    b"ER20 Cmd XX busy",
                    b"ER20 Cmd BG needs mode 3",
                    b"ER25 Cmd BG unreachable at x%",
                    b"ER40 Cmd BG by 10.0.0.300",
                ],
            ),
            (
                NoticeError::UnknownCode,
                &[
                    b"WN21 Work space limit.",
                    b"ER33 J4 PT buffer underflow",
                    b"ER99 what",
                ],
            ),
            (
                NoticeError::Malformed,
                &[b"ER2x Cmd BG busy", b"ER20Cmd BG busy", b"ER"],
            ),
        ];
        for (error, texts) in cases {
            for bytes in texts {
                let text = received(bytes);
                assert_eq!(Notice::parse(&text), Err(error), "{text}");
            }
        }
    }
}
