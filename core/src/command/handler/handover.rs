//! A change of holder: goals, via points, blend tolerances and the `KR` choice belong to the
//! client that set them, so a client that takes control starts with none of them
//! (docs/safety.md, "Who may command the arm"). Its `BG`, `jB`, `VE` or `jE` without its own
//! is refused `ER20 Cmd XX holder changed`, never run to another client's goal.

use armgate_protocol::client::{Command, Notice, Rejection};

use super::CommandHandler;

/// What a change of holder cleared, by kind, until a holder sets its own: the reason a motion
/// start without one gives.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct Cleared {
    /// The `GL`/`GT` goal.
    pub goal: bool,
    /// The `jG` goal.
    pub joint_goal: bool,
    /// Cartesian via points or their blend tolerances (`VP`, `VT`).
    pub cartesian_via: bool,
    /// Joint via points or their blend tolerances (`jV`, `jT`).
    pub joint_via: bool,
}

impl CommandHandler {
    /// Another client now holds the arm (at rest: a holder changes only then): the previous
    /// holder's goals, via points, blend tolerances and `KR` choice go. What an earlier change
    /// cleared stays noted (a client that takes control back finds its goal gone for that).
    pub(super) fn hand_over(&mut self) {
        let c = &mut self.cleared;
        c.goal |= self.goal.take().is_some();
        c.joint_goal |= self.joint_goal.take().is_some();
        c.cartesian_via |= self.controller.clear_cartesian_via();
        c.joint_via |= self.controller.clear_joint_via();
        self.redundancy.clear();
    }

    /// The refusal of `cmd` for want of a goal or via point 0 (`otherwise`): `holder changed`
    /// where the last change of holder cleared one of that kind.
    pub(super) fn missing(&self, cmd: Command, otherwise: Rejection) -> Notice {
        let cleared = match cmd {
            Command::Begin => self.cleared.goal,
            Command::JointBegin => self.cleared.joint_goal,
            Command::ViaExecute => self.cleared.cartesian_via,
            Command::JointExecute => self.cleared.joint_via,
            _ => false,
        };
        Notice::Rejected(
            cmd,
            if cleared {
                Rejection::HolderChanged
            } else {
                otherwise
            },
        )
    }
}
