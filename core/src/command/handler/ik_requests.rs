//! The inverse-kinematics requests: `KG` (move the joints to a pose, on a chosen branch),
//! `KR` (choose the redundancy values of the next `KG`) and `KS` (one IK solution, nothing
//! moves).
//!
//! On a chain without a closed form `KG`'s goal is found by a global search that may take
//! tens of thousands of Newton steps: it runs in slices, one a tick (`handler/planning.rs`),
//! and the `KG` is answered when it ends.

use armgate_protocol::client::branch::NEAREST_BRANCH;
use armgate_protocol::client::redundancy::Redundancy;
use armgate_protocol::client::{Command, Notice, Reply, Request, VALUES};

use super::CommandHandler;
use super::planning::Slow;
use super::replies::{ik_notice, no_measurement, non_negative, refusal_notice, values_reply};
use crate::command::drives::Drives;
use crate::command::ik::{Goal, OUT_OF_REACH};
use crate::command::{ik, redundancy};
use crate::kinematics::{IkResult, Joints};

impl CommandHandler {
    /// `KG`: the joint move to the IK solution of a pose on a branch (with the client's `KR`
    /// choice if the index asks for it).
    pub(super) fn ik_goal(
        &mut self,
        req: &Request,
        drives: &(impl Drives + ?Sized),
    ) -> Result<Reply, Notice> {
        let cmd = req.command;
        // A choice lasts until its client's next KG, whatever the answer.
        let choice = self.redundancy.take(self.client);
        let v = req.values.map(f64::from);
        let duration = non_negative(v[6]).ok_or(Notice::BadNumber(cmd))?;
        self.ready_to_move(cmd, drives)?;
        let (present, _) = self.controller.measured().ok_or(no_measurement(cmd))?;
        let chain = self.controller.chain();
        let ik = self.controller.ik_config();
        let (reference, chosen) =
            ik::reference(chain, present, req.index, choice).map_err(|e| ik_notice(cmd, e))?;
        let goal =
            ik::goal(chain, (&reference, chosen), &v, req.index).map_err(|e| ik_notice(cmd, e))?;
        match goal {
            Goal::Found(goal, branch) => self.move_to_goal(cmd, &goal, duration, branch),
            Goal::Search(target) => {
                let search = chain
                    .global_search(&target, &reference, ik, 0)
                    .map_err(|_| ik_notice(cmd, OUT_OF_REACH))?;
                self.start_planning(Slow::Search(search, duration));
                // Neither sent nor recorded: the answer comes when the search ends.
                Ok(values_reply(cmd, &[0.0; VALUES], NEAREST_BRANCH))
            }
        }
    }

    /// The joint move of a `KG` to `goal` (on `branch`), and its reply.
    fn move_to_goal(
        &mut self,
        cmd: Command,
        goal: &Joints,
        duration: f64,
        branch: u8,
    ) -> Result<Reply, Notice> {
        self.controller
            .move_joints(goal, duration)
            .map_err(|r| refusal_notice(cmd, r))?;
        let mut values = [0.0; VALUES];
        for (o, q) in values.iter_mut().zip(goal.iter()) {
            *o = *q;
        }
        values[VALUES - 1] = duration;
        Ok(values_reply(cmd, &values, branch))
    }

    /// The answer of a `KG` whose global search ended with `result`: the joint move to the
    /// solution found (lasting at least `duration`, s), or out of reach.
    pub(super) fn goal_found(&mut self, result: IkResult, duration: f64) -> Result<Reply, Notice> {
        let cmd = Command::IkGoal;
        match result {
            IkResult::Converged(s) => self.move_to_goal(cmd, &s.q, duration, NEAREST_BRANCH),
            IkResult::NotConverged(_) => Err(ik_notice(cmd, OUT_OF_REACH)),
        }
    }

    /// `KR`: the values of the redundancy parameters for this client's next `KG` (and its
    /// `KS` reads), each within its joint's limits. The reply repeats the choice.
    pub(super) fn choose_redundancy(&mut self, req: &Request) -> Result<Reply, Notice> {
        let cmd = req.command;
        let chain = self.controller.chain();
        let values = ik::choice(chain, &req.values, req.index).map_err(|e| ik_notice(cmd, e))?;
        // The limits as for a joint goal: the chosen values in an otherwise mid-range one.
        let mut q = chain.mid_range();
        redundancy::apply(values, chain.redundancy_parameters(), &mut q);
        self.controller
            .check_joint_goal(&q)
            .map_err(|r| refusal_notice(cmd, r))?;
        self.redundancy.choose(self.client, values);
        let [theta3, theta5] = values.map(|x| x.map(|v| v as f32));
        let (values, index) = Redundancy { theta3, theta5 }.emit();
        Ok(Reply {
            command: cmd,
            values,
            index,
        })
    }

    /// `KS`: an IK solution near the measured joints (mid-range before any measurement), for
    /// the client's `KR` choice if the index asks for it.
    pub(super) fn ik_solution(&self, req: &Request) -> Result<Reply, Notice> {
        let cmd = req.command;
        let v = req.values.map(f64::from);
        let chain = self.controller.chain();
        let present = self
            .controller
            .measured()
            .map_or_else(|| chain.mid_range(), |(q, _)| q);
        let choice = self.redundancy.of(self.client);
        let (reference, _) =
            ik::reference(chain, present, req.index, choice).map_err(|e| ik_notice(cmd, e))?;
        ik::solution(chain, &reference, &v, req.index).map_err(|e| ik_notice(cmd, e))
    }
}
