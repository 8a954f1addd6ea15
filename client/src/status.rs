//! The status request `SQ` (docs/protocol.md, "Status"): mode, drive state, drive fault, joint
//! count, motion, refusals, uptime and the robot's name.
//!
//! Index 0 answers the numbers in f0..f6, index 1 the robot's name as ASCII in bytes 2..30,
//! NUL-padded ([`Client::status`]), index 2 why the arm last stopped or is held
//! ([`Client::stop_cause`]), index 7 the body's nearest gap and its pair ([`Client::nearest`],
//! [`nearest_text`]). A controller older than the request answers
//! `ER00 Cmd SQ not understood`, which becomes [`ClientError::TooOld`]; one without index 2
//! (`ER24`) reports no cause.

use std::fmt;

pub use armgate_protocol::client::Holder;
use armgate_protocol::client::branch::BRANCH_INDEX;
use armgate_protocol::client::signed::{SIGNING_INDEX, SigningReport};
use armgate_protocol::client::{
    CAUSE_INDEX, CauseReport, Command, MESSAGE_LEN, Message, NAME_INDEX, NEAREST_INDEX,
    NearestReport, Obstacle, Reply, RobotName, SESSION_INDEX, STATUS_INDEX, SessionReport,
    StatusReport, VALUES,
};
pub use armgate_protocol::client::{DriveStatus, Motion, StopCause};

use crate::{Client, ClientError, Mode, matching};

/// How a drive state or a motion is shown.
pub trait Name {
    /// `running`, `Cartesian move`, ...
    fn name(self) -> &'static str;
}

impl Name for DriveStatus {
    fn name(self) -> &'static str {
        match self {
            Self::Off => "off",
            Self::Starting => "starting",
            Self::Running => "running",
            Self::Stopping => "stopping",
            Self::Faulted => "faulted",
        }
    }
}

impl Name for Motion {
    fn name(self) -> &'static str {
        match self {
            Self::Holding => "holding",
            Self::JointMove => "joint move",
            Self::CartesianMove => "Cartesian move",
            Self::JointSequence => "joint sequence",
            Self::CartesianSequence => "Cartesian sequence",
            Self::Streaming => "velocity stream",
            Self::Stopping => "stopping",
        }
    }
}

impl Name for StopCause {
    fn name(self) -> &'static str {
        match self {
            Self::Stop => "ST",
            Self::ModeChange => "mode change",
            Self::PowerOff => "OF",
            Self::Workspace => "workspace limit",
            Self::IkDivergence => "IK divergence",
            Self::StreamTimeout => "stream timeout",
            Self::JointLimit => "joint limit",
            Self::ClientSilent => "client silent",
            Self::FollowingError => "following error",
        }
    }
}

/// The controller's state, as the two `SQ` replies report it.
#[derive(Clone, Debug, PartialEq)]
pub struct Status {
    /// The control mode.
    pub mode: Mode,
    /// The drives.
    pub drives: DriveStatus,
    /// The `NN` of the drive fault `ER3x` (0: none).
    pub fault: u8,
    /// The arm's number of joints.
    pub joints: usize,
    /// What moves the arm.
    pub motion: Motion,
    /// How many requests were refused since the controller started.
    pub refused: u64,
    /// Seconds since the controller started.
    pub uptime: f64,
    /// The robot's name (from its robot file).
    pub name: String,
    /// Why the arm last stopped, or is held (`SQ` index 2, asked by [`Client::stop_cause`];
    /// none if not asked, or from older controllers).
    pub cause: Option<CauseReport>,
    /// Who holds the arm, the watchdog, the clients known (`SQ` index 3, asked by
    /// [`Client::session`]; none if not asked, or from older controllers).
    pub session: Option<SessionReport>,
}

impl Status {
    /// Decodes the numbers reply (index 0) and the name reply's bytes (index 1).
    pub fn decode(values: &[f32; VALUES], name: &[u8; MESSAGE_LEN]) -> Result<Self, ClientError> {
        let reply = Reply {
            command: Command::Status,
            values: *values,
            index: STATUS_INDEX,
        };
        let bad = |what: &str| ClientError::InvalidArgument(format!("the status reply has {what}"));
        let report =
            StatusReport::from_reply(&reply).map_err(|e| bad(&format!("{e}: {values:?}")))?;
        let name = Message::new_checked(&name[..])
            .ok()
            .and_then(|m| RobotName::parse(&m).ok())
            .ok_or_else(|| bad("no name"))?;
        let joints = usize::from(report.joints);
        if !(1..=crate::banks::MAX_JOINTS).contains(&joints) {
            return Err(bad(&format!("{joints} joints")));
        }
        Ok(Self {
            mode: report.mode,
            drives: report.drives,
            fault: report.fault,
            joints,
            motion: report.motion,
            refused: u64::from(report.refused),
            uptime: f64::from(report.uptime),
            name: name.as_str().to_owned(),
            cause: None,
            session: None,
        })
    }

    /// The stop or hold cause: `ST`, `joint limit (j6)`, `none`.
    pub fn cause_text(&self) -> String {
        match self.cause {
            Some(CauseReport {
                cause: Some(cause),
                joint,
                by,
            }) => {
                let joint = joint.map_or(String::new(), |j| format!(" (j{})", u16::from(j) + 1));
                let by = by.map_or(String::new(), |a| format!(" from {a}"));
                format!("{}{joint}{by}", cause.name())
            }
            _ => "none".to_owned(),
        }
    }

    /// Who holds the arm: `nobody`, `this client (127.0.0.1:40001)`, `127.0.0.1:40001`.
    pub fn holder_text(&self) -> Option<String> {
        let session = self.session?;
        let address = session.address.map(|a| a.to_string());
        Some(match (session.holder, address) {
            (Holder::Nobody, _) => "nobody".to_owned(),
            (Holder::You, Some(a)) => format!("this client ({a})"),
            (Holder::You, None) => "this client".to_owned(),
            (Holder::Other, Some(a)) => a,
            (Holder::Other, None) => "another client (IPv6)".to_owned(),
        })
    }

    /// The drive state with its fault: `running`, `faulted (ER31)`.
    pub fn drives_text(&self) -> String {
        if self.fault != 0 {
            format!("{} (ER{:02})", self.drives.name(), self.fault)
        } else {
            self.drives.name().to_owned()
        }
    }
}

impl fmt::Display for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "robot      {} ({} joints)", self.name, self.joints)?;
        writeln!(f, "mode       {} ({})", self.mode.name(), self.mode.value())?;
        writeln!(f, "drives     {}", self.drives_text())?;
        writeln!(f, "motion     {}", self.motion.name())?;
        if self.cause.is_some() {
            writeln!(f, "stopped by {}", self.cause_text())?;
        }
        if let (Some(holder), Some(session)) = (self.holder_text(), self.session) {
            writeln!(f, "holder     {holder}")?;
            writeln!(f, "clients    {} known", session.clients)?;
            match session.watchdog_ms {
                0 => writeln!(f, "watchdog   off")?,
                ms => writeln!(f, "watchdog   {ms} ms")?,
            }
        }
        writeln!(f, "refused    {} requests", self.refused)?;
        write!(f, "uptime     {:.1} s", self.uptime)
    }
}

/// `SQ` 7's report as `armgate status` shows it: `99.7 mm, link 6 to box 1 (margin 0.0 mm)`,
/// `link 5 to link 2`, `link 6 to the bounds`; `none (no body)`.
pub fn nearest_text(report: &NearestReport) -> String {
    let Some((gap, hit)) = report.nearest else {
        return "none (no body)".to_owned();
    };
    let what = match hit.obstacle {
        Obstacle::Box(b) => format!("box {b}"),
        Obstacle::Link(l) => format!("link {l}"),
        Obstacle::Bounds => "the bounds".to_owned(),
    };
    format!(
        "{:.1} mm, link {} to {what} (margin {:.1} mm)",
        gap * 1e3,
        hit.link,
        report.margin * 1e3
    )
}

impl Client {
    /// `SQ`: the controller's status (two requests). A controller that does not know the
    /// request is [`ClientError::TooOld`].
    pub fn status(&mut self) -> Result<Status, ClientError> {
        let numbers = self.status_part(STATUS_INDEX)?;
        let name = self.status_part(NAME_INDEX)?;
        Status::decode(&numbers.values, &name.bytes)
    }

    /// `SQ` index 2: why the arm last stopped or is held; `None` from a controller without it.
    pub fn stop_cause(&mut self) -> Result<Option<CauseReport>, ClientError> {
        match self.status_part(CAUSE_INDEX) {
            Ok(reply) => Ok(CauseReport::from_reply(&Reply {
                command: Command::Status,
                values: reply.values,
                index: CAUSE_INDEX,
            })
            .ok()),
            Err(ClientError::Rejected(text)) if matching::code(&text) == Some(24) => Ok(None),
            Err(e) => Err(e),
        }
    }

    /// `SQ` index 3: who holds the arm (this client, another at an address and port, nobody),
    /// the client watchdog, the clients known; `None` from a controller without it.
    pub fn session(&mut self) -> Result<Option<SessionReport>, ClientError> {
        match self.status_part(SESSION_INDEX) {
            Ok(reply) => Ok(SessionReport::from_reply(&Reply {
                command: Command::Status,
                values: reply.values,
                index: SESSION_INDEX,
            })
            .ok()),
            Err(ClientError::Rejected(text)) if matching::code(&text) == Some(24) => Ok(None),
            Err(e) => Err(e),
        }
    }

    /// `SQ` index 7: the smallest gap between the arm's body and what it is checked against
    /// at the measured pose, and the pair; `None` from a controller without it.
    pub fn nearest(&mut self) -> Result<Option<NearestReport>, ClientError> {
        match self.status_part(NEAREST_INDEX) {
            Ok(reply) => NearestReport::from_reply(&Reply {
                command: Command::Status,
                values: reply.values,
                index: NEAREST_INDEX,
            })
            .map(Some)
            .map_err(|e| ClientError::InvalidArgument(format!("a malformed SQ 7 reply: {e}"))),
            Err(ClientError::Rejected(text)) if matching::code(&text) == Some(24) => Ok(None),
            Err(e) => Err(e),
        }
    }

    /// `SQ` index 5: the configuration branch of the measured joints (bits 1 shoulder, 2
    /// elbow, 4 wrist); `None` without a closed form, a measurement, or the report.
    pub fn present_branch(&mut self) -> Result<Option<u8>, ClientError> {
        match self.status_part(BRANCH_INDEX) {
            Ok(reply) => Ok(u8::try_from(reply.values[0] as i32).ok()),
            Err(ClientError::Rejected(text)) if matching::code(&text) == Some(24) => Ok(None),
            Err(e) => Err(e),
        }
    }

    /// `SQ` index 4: the controller's signing policy and counters (docs/protocol.md).
    pub fn signing_report(&mut self) -> Result<SigningReport, ClientError> {
        let raw = self.status_part(SIGNING_INDEX)?;
        let reply = Reply {
            command: Command::Status,
            values: raw.values,
            index: raw.index,
        };
        SigningReport::from_reply(&reply)
            .map_err(|e| ClientError::InvalidArgument(format!("a malformed SQ 4 reply: {e}")))
    }

    fn status_part(&mut self, index: u8) -> Result<crate::RawReply, ClientError> {
        // Raw: the name reply carries text where the floats would be.
        match self.send_raw(Command::Status.chars(), [0.0; VALUES], index) {
            Err(ClientError::Rejected(text)) if matching::code(&text) == Some(0) => {
                Err(ClientError::TooOld {
                    request: "SQ (status)",
                    text,
                })
            }
            other => other,
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::fake::{FakeController, text};

    /// The two replies of a controller in `mode`, drives `drives`, `joints` joints, `name`.
    pub(crate) fn status_reply(request: &[u8], values: [f32; 7], name: &str) -> Vec<u8> {
        let mut reply = vec![0; MESSAGE_LEN];
        reply[..2].copy_from_slice(b"QS");
        reply[30] = request[30];
        if request[30] == NAME_INDEX {
            reply[2..2 + name.len()].copy_from_slice(name.as_bytes());
        } else {
            for (k, v) in values.iter().enumerate() {
                reply[2 + 4 * k..6 + 4 * k].copy_from_slice(&v.to_le_bytes());
            }
        }
        reply
    }

    fn client(fake: &FakeController) -> Client {
        fake.client()
    }

    #[test]
    fn both_replies_are_decoded() {
        let fake = FakeController::spawn(|d| {
            vec![status_reply(
                d,
                [2.0, 4.0, 31.0, 8.0, 3.0, 17.0, 12.5],
                "ranger-mk2",
            )]
        });
        let mut c = client(&fake);
        let mut s = c.status().unwrap();
        s.cause = c.stop_cause().unwrap();
        assert_eq!(
            s,
            Status {
                mode: Mode::Cartesian,
                drives: DriveStatus::Faulted,
                fault: 31,
                joints: 8,
                motion: Motion::JointSequence,
                refused: 17,
                uptime: 12.5,
                name: "ranger-mk2".into(),
                // The fake answers index 2 with the same numbers: cause 2, joint 4.
                cause: Some(CauseReport {
                    cause: Some(StopCause::ModeChange),
                    joint: Some(3),
                    by: Some("0.31.0.8:3".parse().unwrap()),
                }),
                session: None,
            }
        );
        assert_eq!(s.drives_text(), "faulted (ER31)");
        assert_eq!(s.cause_text(), "mode change (j4) from 0.31.0.8:3");
        let sent = fake.received();
        assert_eq!(sent.len(), 3);
        assert_eq!((&sent[0][..2], sent[0][30]), (&b"SQ"[..], 0));
        assert_eq!((&sent[1][..2], sent[1][30]), (&b"SQ"[..], 1));
        assert_eq!((&sent[2][..2], sent[2][30]), (&b"SQ"[..], 2));
        assert!(s.to_string().contains("drives     faulted (ER31)"));
        s.session = Some(SessionReport {
            holder: Holder::Other,
            address: Some("192.168.1.2:40001".parse().unwrap()),
            watchdog_ms: 500,
            send_drops: 0,
            clients: 3,
        });
        let shown = s.to_string();
        assert!(
            shown.contains("holder     192.168.1.2:40001\nclients    3 known\nwatchdog   500 ms\n"),
            "{shown}"
        );
    }

    #[test]
    fn the_nearest_gap_is_decoded_and_shown() {
        let fake = FakeController::spawn(|d| {
            vec![status_reply(d, [0.0125, 5.0, 1.0, 2.0, 0.01, 0.0, 0.0], "")]
        });
        let report = client(&fake).nearest().unwrap().unwrap();
        assert_eq!(
            nearest_text(&report),
            "12.5 mm, link 5 to link 2 (margin 10.0 mm)"
        );
        assert_eq!(fake.received()[0][30], NEAREST_INDEX);
        let none = NearestReport {
            nearest: None,
            margin: 0.0,
        };
        assert_eq!(nearest_text(&none), "none (no body)");
        let old = FakeController::spawn(|_| vec![text("ER24 Cmd SQ bad index")]);
        assert_eq!(client(&old).nearest().unwrap(), None);
    }

    #[test]
    fn an_old_controller_is_too_old() {
        let fake = FakeController::spawn(|_| vec![text("ER00 Cmd SQ not understood")]);
        let err = client(&fake).status().unwrap_err();
        assert!(
            err.to_string().contains("too old"),
            "{err}: the controller's text is kept"
        );
        assert!(matches!(err, ClientError::TooOld { .. }));
    }

    #[test]
    fn nonsense_values_are_errors() {
        let name = [0; MESSAGE_LEN];
        for values in [
            [7.0, 2.0, 0.0, 6.0, 0.0, 0.0, 1.0],
            [1.0, 9.0, 0.0, 6.0, 0.0, 0.0, 1.0],
            [1.0, 2.0, 0.0, 0.0, 0.0, 0.0, 1.0],
            [1.0, 2.0, 0.0, 9.0, 0.0, 0.0, 1.0],
            [1.0, 2.0, 0.0, 6.0, 0.5, 0.0, 1.0],
            [1.0, 2.0, 0.0, 6.0, 0.0, f32::NAN, 1.0],
        ] {
            assert!(Status::decode(&values, &name).is_err(), "{values:?}");
        }
    }
}
