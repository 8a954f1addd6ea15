//! How a wait that did not arrive ends: why the arm stopped (the controller's own cause,
//! `SQ` index 2, and who set it), and `ST` from the client that started the motion, so that the
//! arm never goes on alone after its client gave up on it (issue 33, item 7; issue 37).

use std::fmt;
use std::net::{SocketAddr, SocketAddrV4};

use crate::status::StopCause;
use crate::{Client, ClientError};

/// Who stopped a motion.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stopper {
    /// The controller itself: the workspace, IK divergence, a stream's timeout or joint limit,
    /// the client watchdog.
    Controller,
    /// This client (another request of its own, e.g. from a second thread).
    ThisClient,
    /// Another client, at this address and port.
    Client(SocketAddrV4),
    /// A client the controller does not name (an IPv6 one, or a controller older than the
    /// report).
    UnknownClient,
}

impl Stopper {
    /// Who set `cause`, from the address `SQ` 2 reports and this client's own.
    pub fn of(cause: StopCause, by: Option<SocketAddrV4>, own: Option<SocketAddr>) -> Self {
        match cause {
            StopCause::Stop | StopCause::ModeChange | StopCause::PowerOff => match by {
                Some(a) if own == Some(SocketAddr::V4(a)) => Self::ThisClient,
                Some(a) => Self::Client(a),
                None => Self::UnknownClient,
            },
            _ => Self::Controller,
        }
    }
}

impl fmt::Display for Stopper {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Controller => f.write_str("the controller"),
            Self::ThisClient => f.write_str("this client"),
            Self::Client(a) => write!(f, "client {a}"),
            Self::UnknownClient => f.write_str("another client"),
        }
    }
}

/// What a client did about the motion when its wait ended without arriving.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum EndStop {
    /// It sent `ST`: the arm stops and holds.
    Sent,
    /// `ST` got no answer or was refused.
    Failed(String),
    /// It was told not to stop on Ctrl-C: the motion goes on.
    Left,
}

impl fmt::Display for EndStop {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Sent => f.write_str("sent ST: the arm stops and holds"),
            Self::Failed(e) => write!(f, "ST failed ({e}): the arm may still be moving"),
            Self::Left => f.write_str("no ST sent, as asked: the arm goes on moving"),
        }
    }
}

/// When a wait that did not arrive sends `ST` ([`WaitOptions::stop`](crate::WaitOptions::stop)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StopPolicy {
    /// On every ending but arrival (the default): interrupt, timeout, stall, no reply.
    #[default]
    Always,
    /// As [`Always`](Self::Always), but an interrupt leaves the motion running (and says so).
    ExceptInterrupt,
    /// Never: the caller decides (the error is returned as it is).
    Never,
}

impl Client {
    /// A wait that stalled or timed out, told apart from one the controller stopped: if `SQ` 2
    /// reports a stop cause in force (the motion's start cleared the previous one), the error
    /// becomes [`ClientError::Stopped`] with the cause and who set it. Asked before this
    /// client's own `ST`, which would replace the cause. Best effort: without an answer the
    /// error stays.
    pub(crate) fn explain(&mut self, error: ClientError) -> ClientError {
        let (ClientError::Stalled { target, .. } | ClientError::WaitTimeout { target, .. }) = error
        else {
            return error;
        };
        let Ok(Some(report)) = self.stop_cause() else {
            return error;
        };
        let Some(cause) = report.cause else {
            return error;
        };
        ClientError::Stopped {
            cause,
            joint: report.joint,
            by: Stopper::of(cause, report.by, self.local_addr().ok()),
            target,
        }
    }

    /// Ends a wait this client owned that did not arrive: sends `ST` as `policy` says and
    /// returns the error with what was done ([`ClientError::Ended`]). A motion the controller
    /// already stopped or aborted is not stopped again (that would replace its cause).
    pub fn end_wait(&mut self, error: ClientError, policy: StopPolicy) -> ClientError {
        if matches!(
            error,
            ClientError::Stopped { .. } | ClientError::Aborted(_) | ClientError::Ended { .. }
        ) {
            return error;
        }
        let stop = match (policy, &error) {
            (StopPolicy::Never, _) => return error,
            (StopPolicy::ExceptInterrupt, ClientError::Interrupted) => EndStop::Left,
            _ => match self.stop() {
                Ok(()) => EndStop::Sent,
                Err(e) => EndStop::Failed(e.to_string()),
            },
        };
        ClientError::Ended {
            error: Box::new(error),
            stop,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_client_cause_names_the_client_and_a_controller_cause_the_controller() {
        let a: SocketAddrV4 = "127.0.0.1:40001".parse().unwrap();
        let own: SocketAddr = "127.0.0.1:40002".parse().unwrap();
        assert_eq!(
            Stopper::of(StopCause::Stop, Some(a), Some(own)),
            Stopper::Client(a)
        );
        assert_eq!(
            Stopper::of(StopCause::PowerOff, Some(a), Some(SocketAddr::V4(a))),
            Stopper::ThisClient
        );
        assert_eq!(
            Stopper::of(StopCause::ModeChange, None, Some(own)),
            Stopper::UnknownClient
        );
        assert_eq!(
            Stopper::of(StopCause::Workspace, Some(a), Some(own)),
            Stopper::Controller
        );
        assert_eq!(Stopper::Client(a).to_string(), "client 127.0.0.1:40001");
    }
}
