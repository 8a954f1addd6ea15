//! Why the arm stopped or holds: what `SQ` index 2 reports (docs/protocol.md).

use core::net::{Ipv4Addr, SocketAddrV4};

use super::{Command, DecodeError, Reply};

/// `SQ` index of the stop or hold cause in force.
pub const CAUSE_INDEX: u8 = 2;

/// Why the controller brought the arm to rest, or holds it where a command would drive it on.
/// The code is `QS` index 2's f0; [`joint`](CauseReport::joint) names the joint of a limit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StopCause {
    /// `ST` or `jR`.
    Stop = 1,
    /// `CM` while moving: the arm decelerates, then the new mode holds.
    ModeChange = 2,
    /// `OF` while moving: the arm decelerates, then the drives stop.
    PowerOff = 3,
    /// The tool would leave the workspace or enter an exclusion box (`ER21`).
    Workspace = 4,
    /// The tracking IK lost the Cartesian set-point (`WN22`).
    IkDivergence = 5,
    /// A velocity stream's command timed out.
    StreamTimeout = 6,
    /// A stream holds a joint at the margin before its limit (`WN12 jN at limit`).
    JointLimit = 7,
    /// The controlling client was silent for longer than its watchdog (`ER41`).
    ClientSilent = 8,
    /// A joint's measured position fell further behind (or ahead of) its command than the
    /// robot file allows (`ER43 jN following error E`).
    FollowingError = 9,
}

impl StopCause {
    /// Every cause, by code.
    pub const ALL: [Self; 9] = [
        Self::Stop,
        Self::ModeChange,
        Self::PowerOff,
        Self::Workspace,
        Self::IkDivergence,
        Self::StreamTimeout,
        Self::JointLimit,
        Self::ClientSilent,
        Self::FollowingError,
    ];

    /// The cause with this code.
    pub fn from_code(code: u8) -> Option<Self> {
        Self::ALL.into_iter().find(|c| *c as u8 == code)
    }
}

/// The `QS` reply to `SQ` index 2: the cause in force (f0, 0 for none) and, for a joint limit,
/// the joint (f1, 1-based; 0 otherwise); for a cause a client's request set (`ST`, `jR`, `CM`,
/// `OF`), that client's IPv4 address as f2/f3 (upper and lower 16 bits, as `SQ` 3 gives the
/// holder's) and its port as f4 (all 0 for the controller's own causes or an IPv6 client), so
/// that a client whose motion was stopped can say by whom.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CauseReport {
    /// The cause in force: the last stop's until the next motion starts, or a stream's hold.
    pub cause: Option<StopCause>,
    /// The joint a [`StopCause::JointLimit`] holds, or the one a [`StopCause::FollowingError`]
    /// was found on (0-based).
    pub joint: Option<u8>,
    /// The client whose request set the cause, if a client did and its address is IPv4.
    pub by: Option<SocketAddrV4>,
}

impl CauseReport {
    /// The reply, index 2.
    pub fn to_reply(&self) -> Reply {
        let code = self.cause.map_or(0, |c| c as u8);
        let joint = self.joint.map_or(0, |j| j.saturating_add(1));
        let ip = self.by.map_or(0, |a| u32::from(*a.ip()));
        Reply {
            command: Command::Status,
            values: [
                f32::from(code),
                f32::from(joint),
                f32::from((ip >> 16) as u16),
                f32::from(ip as u16),
                f32::from(self.by.map_or(0, |a| a.port())),
                0.0,
                0.0,
            ],
            index: CAUSE_INDEX,
        }
    }

    /// Decodes a `QS` index-2 reply (on the client side). A cause this client does not know
    /// (a newer controller's) reads as none.
    pub fn from_reply(reply: &Reply) -> Result<Self, DecodeError> {
        if reply.command != Command::Status || reply.index != CAUSE_INDEX {
            return Err(DecodeError::WrongCommand);
        }
        let [code, joint, high, low, port, ..] = reply.values;
        let (code, joint) = (code as u8, joint as u8);
        let ip = (u32::from(high as u16) << 16) | u32::from(low as u16);
        Ok(Self {
            cause: StopCause::from_code(code),
            joint: joint.checked_sub(1),
            by: (ip != 0).then(|| SocketAddrV4::new(Ipv4Addr::from(ip), port as u16)),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reports_round_trip() {
        let report = CauseReport {
            cause: Some(StopCause::JointLimit),
            joint: Some(5),
            by: None,
        };
        let reply = report.to_reply();
        assert_eq!(reply.values[..5], [7.0, 6.0, 0.0, 0.0, 0.0]);
        assert_eq!(CauseReport::from_reply(&reply), Ok(report));
        let stopped = CauseReport {
            cause: Some(StopCause::Stop),
            joint: None,
            by: Some("192.168.1.2:40001".parse().unwrap()),
        };
        let reply = stopped.to_reply();
        assert_eq!(reply.values[..5], [1.0, 0.0, 49320.0, 258.0, 40001.0]);
        assert_eq!(CauseReport::from_reply(&reply), Ok(stopped));
        let none = CauseReport {
            cause: None,
            joint: None,
            by: None,
        };
        assert_eq!(CauseReport::from_reply(&none.to_reply()), Ok(none));
    }
}
