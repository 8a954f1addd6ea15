//! Telling the reply to a request apart from everything else the controller sends.
//!
//! The protocol has no sequence numbers. A datagram is the reply to a request if
//!
//! * it is a normal reply whose characters are the request's reversed (`BG` → `GB`), and, for
//!   the commands that echo their index, the index matches: the via slot (bits 0–6) for `jV` and
//!   `VP`, the bank bit (bit 7) for `jP` and `TM`, the whole index for `TW` and `jW`; or
//! * it is an `ER` text that names the request's characters (`ER20 Cmd BG rejected`,
//!   `ER00 Cmd XX not understood`, `ER01 Msg XX undersized.`), or `ER10` for `OF` / `ER11` for
//!   `ON`: the request was refused.
//!
//! Every other `ER`/`WN` text is an unsolicited notice (`ER21`, `WN12`, `WN22`, `WN27`, drive
//! faults `ER3x`, or a refusal of an earlier request). Every other normal reply is stale (the
//! late answer to an earlier, retried request) and is dropped.

use armgate_protocol::client::banks::BANK_2;
use armgate_protocol::client::{Header, Message, Text};

/// What a received datagram is, relative to the request being waited for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Incoming {
    /// The reply (its bytes are the datagram's first 31).
    Reply,
    /// An error text answering the request.
    Rejected(Text),
    /// An `ER`/`WN` text that does not answer the request.
    Notice(Text),
    /// A normal reply to something else, or a datagram that is not a message at all.
    Other,
}

/// The reply a request waits for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Expect {
    /// The request's characters.
    pub chars: [u8; 2],
    /// The request's index byte.
    pub index: u8,
}

impl Expect {
    /// Whether a reply's index fits the request's.
    fn index_matches(&self, index: u8) -> bool {
        match &self.chars {
            b"jV" | b"VP" => index & !BANK_2 == self.index & !BANK_2,
            b"jP" | b"TM" => index & BANK_2 == self.index & BANK_2,
            // The streams echo their index: the frame bit of TW, the bank bit of jW.
            b"TW" | b"jW" => index == self.index,
            // The status request: index 0 the numbers, index 1 the name.
            b"SQ" => index == self.index,
            _ => true,
        }
    }

    /// Whether an error text answers this request (the grammar's [`Header::refuses`]).
    fn is_answered_by(&self, text: &Text) -> bool {
        Header::parse(text).is_ok_and(|h| h.refuses() == Some(self.chars))
    }

    /// Classifies a received datagram.
    pub fn classify(&self, datagram: &[u8]) -> Incoming {
        let Ok(message) = Message::new_checked(datagram) else {
            return Incoming::Other;
        };
        if let Ok(text) = Text::parse(&message) {
            return if self.is_answered_by(&text) {
                Incoming::Rejected(text)
            } else {
                Incoming::Notice(text)
            };
        }
        let [a, b] = self.chars;
        if message.command() == [b, a] && self.index_matches(message.index()) {
            Incoming::Reply
        } else {
            Incoming::Other
        }
    }
}

/// Classifies a datagram when no request is outstanding: texts are notices, the rest is stale.
pub fn classify_unsolicited(datagram: &[u8]) -> Incoming {
    match Message::new_checked(datagram)
        .ok()
        .and_then(|m| Text::parse(&m).ok())
    {
        Some(text) => Incoming::Notice(text),
        None => Incoming::Other,
    }
}

/// The two-digit code of a text (`ER21` → 21), if it has one.
pub fn code(text: &Text) -> Option<u8> {
    Header::parse(text).ok().map(|h| h.code)
}

/// Whether a notice means that a running motion will not complete (the grammar's
/// [`Header::ends_motion`]: `ER21`, `WN22`, `WN27`, `ER41` and the drive faults `ER3x`).
pub fn ends_motion(text: &Text) -> bool {
    Header::parse(text).is_ok_and(|h| h.ends_motion())
}

#[cfg(test)]
mod tests {
    use super::*;
    use armgate_protocol::client::{Command, DriveStatus, MESSAGE_LEN, Notice, Reply};

    fn text(s: &str) -> [u8; MESSAGE_LEN] {
        let mut b = [0; MESSAGE_LEN];
        b[..s.len()].copy_from_slice(s.as_bytes());
        b
    }

    fn expect(chars: &[u8; 2], index: u8) -> Expect {
        Expect {
            chars: *chars,
            index,
        }
    }

    #[test]
    fn reversed_characters_are_the_reply() {
        let e = expect(b"BG", 0);
        assert_eq!(
            e.classify(&Reply::null(Command::Begin).to_bytes()),
            Incoming::Reply
        );
        assert_eq!(
            e.classify(&Reply::null(Command::Pose).to_bytes()),
            Incoming::Other
        );
        // VC is answered CV (the seed's PV is not accepted).
        let vc = expect(b"VC", 0);
        assert_eq!(vc.classify(&text("CV")), Incoming::Reply);
        assert_eq!(vc.classify(&text("PV")), Incoming::Other);
        assert_eq!(expect(b"RC", 0).classify(&text("CR")), Incoming::Reply);
    }

    #[test]
    fn index_echo_is_checked_where_the_protocol_echoes_it() {
        let mut vj = Reply::null(Command::JointVia);
        vj.index = 0x83;
        assert_eq!(
            expect(b"jV", 0x83).classify(&vj.to_bytes()),
            Incoming::Reply
        );
        // A controller that echoes only the slot of a bank-2 request is accepted too.
        vj.index = 3;
        assert_eq!(
            expect(b"jV", 0x83).classify(&vj.to_bytes()),
            Incoming::Reply
        );
        assert_eq!(expect(b"jV", 4).classify(&vj.to_bytes()), Incoming::Other);
        let mut pj = Reply::null(Command::JointPosition);
        pj.index = BANK_2;
        assert_eq!(
            expect(b"jP", BANK_2).classify(&pj.to_bytes()),
            Incoming::Reply
        );
        assert_eq!(expect(b"jP", 0).classify(&pj.to_bytes()), Incoming::Other);
        // Null replies need not echo anything.
        assert_eq!(expect(b"jG", BANK_2).classify(&text("Gj")), Incoming::Reply);
    }

    #[test]
    fn texts_naming_the_request_are_rejections() {
        let e = expect(b"BG", 0);
        for s in [
            "ER20 Cmd BG rejected",
            "ER24 Cmd BG outside workspace",
            "ER00 Cmd BG not understood",
            "ER01 Msg BG undersized.",
        ] {
            assert!(matches!(e.classify(&text(s)), Incoming::Rejected(t) if t.as_str() == s));
        }
        assert!(matches!(
            e.classify(&text("ER20 Cmd jB rejected")),
            Incoming::Notice(_)
        ));
        assert!(matches!(
            expect(b"ON", 0).classify(
                &Notice::ArmDidNotStart(DriveStatus::Running)
                    .text()
                    .to_bytes()
            ),
            Incoming::Rejected(_)
        ));
        assert!(matches!(
            expect(b"OF", 0).classify(&Notice::ArmDidNotStop(DriveStatus::Off).text().to_bytes()),
            Incoming::Rejected(_)
        ));
        assert!(matches!(
            expect(b"PS", 0).classify(
                &Notice::ArmDidNotStart(DriveStatus::Running)
                    .text()
                    .to_bytes()
            ),
            Incoming::Notice(_)
        ));
    }

    #[test]
    fn unsolicited_texts_are_notices() {
        let e = expect(b"PS", 0);
        for s in [
            "ER21 Work space limit.",
            "WN12 Joint limit.",
            "WN22 Inv Kin Divergence.",
            "WN27 Via point missed.",
            "ER31 Drive 2 fault",
        ] {
            assert!(matches!(e.classify(&text(s)), Incoming::Notice(t) if t.as_str() == s));
        }
        assert_eq!(e.classify(b"SP"), Incoming::Other);
    }

    #[test]
    fn motion_ending_notices() {
        let parse = |s: &str| {
            let b = text(s);
            Text::parse(&Message::new_checked(&b[..]).unwrap()).unwrap()
        };
        assert!(ends_motion(&parse("ER21 Work space limit.")));
        assert!(ends_motion(&parse("WN22 Inv Kin Divergence.")));
        assert!(ends_motion(&parse("WN27 Via point missed.")));
        for notice in [
            Notice::WorkspaceLimit,
            Notice::IkDivergence,
            Notice::ViaPointMissed,
        ] {
            assert!(ends_motion(&notice.text()), "{notice:?}");
        }
        assert!(!ends_motion(&Notice::JointLimit.text()));
        assert!(ends_motion(&parse("ER33 Drive fault")));
        assert!(!ends_motion(&parse("WN12 Joint limit.")));
        assert!(!ends_motion(&parse("ER20 Cmd BG rejected")));
    }
}
