//! The inverse-kinematics requests: `KG` (move the joints to a pose, on a chosen branch),
//! `KR` (choose the redundancy values of the next `KG`) and `KS` (one IK solution, nothing
//! moves).

use armgate_protocol::client::redundancy::Redundancy;
use armgate_protocol::client::{Notice, Reply, Request, VALUES};

use super::CommandHandler;
use super::replies::{ik_notice, no_measurement, non_negative, refusal_notice, values_reply};
use crate::command::drives::Drives;
use crate::command::{ik, redundancy};

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
        let (goal, branch) = ik::goal(chain, ik, (&reference, chosen), &v, req.index)
            .map_err(|e| ik_notice(cmd, e))?;
        self.controller
            .move_joints(&goal, duration)
            .map_err(|r| refusal_notice(cmd, r))?;
        let mut values = [0.0; VALUES];
        for (o, q) in values.iter_mut().zip(goal.iter()) {
            *o = *q;
        }
        values[VALUES - 1] = duration;
        Ok(values_reply(cmd, &values, branch))
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
