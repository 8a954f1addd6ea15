//! Why a request or a wait failed.

use std::io;
use std::net::SocketAddr;
use std::time::Duration;

use armgate_protocol::client::Text;

/// Everything that can go wrong talking to the controller.
///
/// [`exit_code`](Self::exit_code) maps each case to the exit status of the `armgate` tool: 1 when
/// the controller said no (a rejection, or a notice that ended a motion), 2 for everything else
/// (no answer, I/O, bad arguments).
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
    /// A wait ended because it was interrupted (Ctrl-C); the motion was not stopped.
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
    /// The exit status for the `armgate` tool: 1 if the controller refused or aborted, else 2.
    pub fn exit_code(&self) -> u8 {
        match self {
            Self::Rejected(_) | Self::Aborted(_) | Self::TooOld { .. } | Self::NotStarted(_) => 1,
            // 128 + SIGINT, as a shell reports a process ended by Ctrl-C.
            Self::Interrupted => 130,
            _ => 2,
        }
    }
}
