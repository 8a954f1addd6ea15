//! Why a request or a wait failed.

use std::io;
use std::net::SocketAddr;
use std::time::Duration;

use armgate_protocol::client::Text;

use crate::ended::{EndStop, Stopper};
use crate::exit;
use crate::status::{Name, StopCause};

/// Everything that can go wrong talking to the controller.
///
/// [`exit_code`](Self::exit_code) maps each case to the exit status of the `armgate` tool, one
/// table for every subcommand ([`exit::TABLE`]).
#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    /// A socket operation failed.
    #[error("I/O error: {0}")]
    Io(#[from] io::Error),
    /// The controller address could not be parsed or resolved.
    #[error("bad controller address: {0}")]
    Address(String),
    /// No reply arrived: every attempt (the first send and each retry) timed out.
    #[error("no reply to {command} after {attempts} attempt(s) of {timeout:?} each")]
    Timeout {
        /// The request's two characters.
        command: String,
        /// How many times the datagram was sent.
        attempts: u32,
        /// The time waited after each send.
        timeout: Duration,
    },
    /// No answer signed with the key came, but other datagrams did: the controller has no key
    /// or another one, or someone else answers.
    #[error(
        "no signed answer to {command}: {count} datagram(s) came unsigned or not signed with \
         the key (has the controller this key?)"
    )]
    Unverified {
        /// The request's two characters.
        command: String,
        /// Datagrams dropped while waiting.
        count: u64,
    },
    /// The operating system reported the controller's port as closed (ICMP port unreachable).
    #[error("nothing listens at {0} (connection refused); is the controller running?")]
    Refused(SocketAddr),
    /// The controller answered the request with an error text, e.g. `ER20 Cmd BG rejected`.
    #[error("{0}")]
    Rejected(Text),
    /// A wait ended because the controller reported that the motion cannot complete
    /// (`ER21`, `WN22`, `WN27` or a drive fault `ER3x`).
    #[error("motion aborted: {0}")]
    Aborted(Text),
    /// A wait ended because the controller stopped the motion before the target was reached,
    /// for `cause` (`SQ` index 2; `joint` names a joint limit's joint, 0-based), set by `by`.
    #[error(
        "the motion was stopped by {by}: {}{} (target {} not reached)",
        cause.name(), joint.map_or(String::new(), |j| format!(" (j{})", u16::from(j) + 1)),
        target + 1
    )]
    Stopped {
        /// Why the controller stopped it.
        cause: StopCause,
        /// The joint of a joint-limit hold (0-based).
        joint: Option<u8>,
        /// Who stopped it.
        by: Stopper,
        /// The 0-based number of the target not reached.
        target: usize,
    },
    /// A wait this client owned ended without arriving; `stop` says whether it sent `ST`.
    #[error("{error}; {stop}")]
    Ended {
        /// Why the wait ended.
        error: Box<ClientError>,
        /// What this client did about the motion.
        stop: EndStop,
    },
    /// A wait ended because the arm stopped moving before it reached the target.
    #[error(
        "the arm stopped {} from target {} (no motion for {after:?})",
        remaining(*distance, *angle), target + 1
    )]
    Stalled {
        /// The 0-based number of the target not reached.
        target: usize,
        /// The remaining distance (m for poses, rad for joints).
        distance: f64,
        /// For poses: the remaining angle (rad).
        angle: Option<f64>,
        /// How long the arm had not moved.
        after: Duration,
    },
    /// A wait ran out of time.
    #[error(
        "target {} not reached within {timeout:?} (still {} from it)",
        target + 1, remaining(*distance, *angle)
    )]
    WaitTimeout {
        /// The 0-based number of the target not reached.
        target: usize,
        /// The remaining distance (m for poses, rad for joints).
        distance: f64,
        /// For poses: the remaining angle (rad).
        angle: Option<f64>,
        /// The time allowed.
        timeout: Duration,
    },
    /// The controller does not know a request (it answered `ER00`): it is older than this
    /// client.
    #[error("the controller is too old for {request}: it answered `{text}`")]
    TooOld {
        /// The request, e.g. `SQ (status)`.
        request: &'static str,
        /// The controller's answer.
        text: Text,
    },
    /// ON was answered but the drives do not run (faulted, off, or still starting).
    #[error("the drives did not start: {0}")]
    NotStarted(String),
    /// A wait ended because it was interrupted (Ctrl-C).
    #[error("interrupted")]
    Interrupted,
    /// An argument cannot be sent (e.g. too many joints, a via slot with bit 7 set).
    #[error("{0}")]
    InvalidArgument(String),
}

/// The remaining distance, in mm and rad for poses, in rad (or m) for joints.
fn remaining(distance: f64, angle: Option<f64>) -> String {
    match angle {
        Some(a) => format!("{:.1} mm and {a:.3} rad", distance * 1e3),
        None => format!("{distance:.4} (joint norm)"),
    }
}

impl ClientError {
    /// The exit status for the `armgate` tool: its row of [`exit::TABLE`].
    pub fn exit_code(&self) -> u8 {
        match self {
            Self::Rejected(_) | Self::TooOld { .. } | Self::NotStarted(_) => exit::REFUSED,
            Self::Aborted(_) | Self::Stopped { .. } => exit::STOPPED,
            Self::Stalled { .. } | Self::WaitTimeout { .. } => exit::NOT_ARRIVED,
            Self::Interrupted => exit::INTERRUPTED,
            Self::Ended { error, .. } => error.exit_code(),
            Self::Io(_)
            | Self::Address(_)
            | Self::Timeout { .. }
            | Self::Unverified { .. }
            | Self::Refused(_)
            | Self::InvalidArgument(_) => exit::NO_CONTACT,
        }
    }
}
