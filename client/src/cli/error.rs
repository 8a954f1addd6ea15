//! Why an `armgate` command failed, and its exit status.

use crate::{ClientError, RunFileError, Text};

/// Why a command failed.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// From the client.
    #[error(transparent)]
    Client(#[from] ClientError),
    /// A bad run file.
    #[error(transparent)]
    RunFile(#[from] RunFileError),
    /// A bad argument.
    #[error("{0}")]
    Usage(String),
    /// Writing the output failed.
    #[error("output: {0}")]
    Output(#[from] std::io::Error),
    /// `armgate plot` failed.
    #[error(transparent)]
    Plot(#[from] crate::plot::PlotError),
    /// The controller refused a request; the hint says what would help.
    #[error("{text}")]
    Refused {
        /// The refusal, with its reason.
        text: Text,
        /// What to do about it.
        hint: Option<String>,
    },
    /// Ctrl-C during a wait; says whether ST was sent.
    #[error("interrupted: {0}")]
    Interrupted(String),
    /// A command that started a motion failed before it saw it end; ST was sent first.
    #[error("{error}; {stop}")]
    Stopped {
        /// Why the command failed.
        error: ClientError,
        /// Whether ST was sent.
        stop: String,
    },
}

impl CliError {
    /// 1 if the controller refused or aborted, 130 if interrupted, else 2.
    pub fn exit_code(&self) -> u8 {
        match self {
            Self::Client(e) => e.exit_code(),
            Self::Refused { .. } => 1,
            Self::Interrupted(_) => ClientError::Interrupted.exit_code(),
            Self::Stopped { error, .. } => error.exit_code(),
            _ => 2,
        }
    }

    /// Whether the error is a closed output pipe (`armgate pose | head -1`): not worth a word.
    pub(super) fn is_broken_pipe(&self) -> bool {
        matches!(self, Self::Output(e) if e.kind() == std::io::ErrorKind::BrokenPipe)
    }
}
