//! Why an `armgate` command failed, and its exit status.

use crate::{ClientError, RunFileError, Text, exit};

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
    /// Ctrl-C during a stream (`jog`): says what the arm does.
    #[error("interrupted: {0}")]
    Interrupted(String),
    /// `armgate ik`: the pose has no solution within the joint limits.
    #[error("{0}")]
    NoSolution(String),
}

impl CliError {
    /// The command's row of [`exit::TABLE`], the same for every subcommand.
    pub fn exit_code(&self) -> u8 {
        match self {
            Self::Client(e) => e.exit_code(),
            Self::Refused { .. } => exit::REFUSED,
            Self::Interrupted(_) => exit::INTERRUPTED,
            Self::NoSolution(_) => exit::NO_SOLUTION,
            Self::RunFile(_) | Self::Usage(_) | Self::Output(_) | Self::Plot(_) => exit::NO_CONTACT,
        }
    }

    /// Whether the error is a closed output pipe (`armgate pose | head -1`): not worth a word.
    pub(super) fn is_broken_pipe(&self) -> bool {
        matches!(self, Self::Output(e) if e.kind() == std::io::ErrorKind::BrokenPipe)
    }
}
