//! Planning requests whose work takes several ticks: `KG`'s global search on a chain without
//! a closed form, and the line check of `BG` and `VE` (every point of a line checked for the
//! whole arm). The work runs in slices ([`Slice`]), one a tick in the cycle's planning slot
//! (`cycle::budget`), and the request is answered when it ends (by the cycle; direct callers
//! of the handler finish it at once). A stop cancels it ([`cancel_planning`]).
//!
//! [`cancel_planning`]: CommandHandler::cancel_planning

use armgate_protocol::client::{Command, MESSAGE_LEN, Notice, Rejection, Reply};
use core::net::SocketAddr;

use super::CommandHandler;
use crate::command::drives::Drives;
use crate::kinematics::GlobalSearch;
use crate::motion::CartesianPlan;

/// How much of a planning request's work one slice does at most.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Slice {
    /// Newton steps of a `KG`'s global search.
    pub steps: u16,
    /// Work of a `BG`'s or `VE`'s line check: each point of a line (its solve and the whole
    /// arm's check there) `motion::POINT_WORK`, and one per Newton iteration of its solve.
    pub line_work: u16,
}

impl Slice {
    /// All of the work at once (more than any request's budget).
    pub const WHOLE: Self = Self {
        steps: u16::MAX,
        line_work: u16::MAX,
    };
}

/// The work of a planning request in progress (one at a time, in place: no heap to box the
/// larger variant in).
#[derive(Clone, Debug)]
#[allow(clippy::large_enum_variant)]
pub(super) enum Slow {
    /// `KG`'s global search, and the duration of its move (s).
    Search(GlobalSearch, f64),
    /// The line check of `BG` or `VE` (the command), and the motion that starts after it.
    Lines(Command, CartesianPlan),
}

/// A planning request whose work runs in slices across ticks.
#[derive(Clone, Debug)]
pub(super) struct Planning {
    work: Slow,
    client: SocketAddr,
    /// The request that started it is still being answered (its reply is not the answer).
    fresh: bool,
}

impl Planning {
    /// The request that started it is still being answered.
    pub(super) fn is_fresh(&self) -> bool {
        self.fresh
    }

    /// The request's command.
    fn command(&self) -> Command {
        match self.work {
            Slow::Search(..) => Command::IkGoal,
            Slow::Lines(cmd, _) => cmd,
        }
    }
}

impl CommandHandler {
    /// Leaves `work` to run in slices for the client of the request being handled: the
    /// request's own reply is then neither sent nor recorded.
    pub(super) fn start_planning(&mut self, work: Slow) {
        self.planning = Some(Planning {
            work,
            client: self.client,
            fresh: true,
        });
    }

    /// True once, just after a request started work that runs in slices: its answer comes
    /// from [`continue_planning`](Self::continue_planning), not from the request's own reply.
    pub fn planning_started(&mut self) -> bool {
        self.planning
            .as_mut()
            .is_some_and(|p| core::mem::replace(&mut p.fresh, false))
    }

    /// Runs the planning work on for one `slice`; once it has ended, starts the motion (if the
    /// arm may still move for its client) and returns the answer to `datagram`, the request
    /// that started it. Ended early if the client no longer holds the arm, or the arm may no
    /// longer move.
    pub fn continue_planning(
        &mut self,
        slice: Slice,
        datagram: &[u8],
        drives: &(impl Drives + ?Sized),
    ) -> Option<[u8; MESSAGE_LEN]> {
        let (client, cmd) = self.planning.as_ref().map(|p| (p.client, p.command()))?;
        let ready = self.ready_to_move(cmd, drives);
        let pending = self.planning.as_mut()?;
        let answer = if self.session.holder() != Some(client) {
            // Another client took control meanwhile (the arm at rest): not its motion to run.
            Err(Notice::Rejected(cmd, Rejection::HolderChanged))
        } else if let Err(notice) = ready {
            Err(notice)
        } else {
            match &mut pending.work {
                Slow::Search(search, duration) => {
                    let duration = *duration;
                    let result = self
                        .controller
                        .chain()
                        .continue_search(search, slice.steps)?;
                    self.goal_found(result, duration)
                }
                Slow::Lines(_, plan) => {
                    let result = self
                        .controller
                        .continue_plan(plan, usize::from(slice.line_work))?;
                    self.lines_checked(cmd, result)
                }
            }
        };
        self.planning = None;
        self.client = client;
        let reply = answer
            .map(|r: Reply| r.to_bytes())
            .unwrap_or_else(|notice| self.refuse(notice));
        self.session
            .answered(client, cmd, datagram, &reply, self.now);
        Some(reply)
    }

    /// Drops the planning work in progress (a stop cancelled it).
    pub fn cancel_planning(&mut self) {
        self.planning = None;
    }
}
