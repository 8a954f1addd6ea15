//! The inverse-kinematics requests: `KG` (move the joints to a pose, on a chosen branch) and
//! `KS` (one IK solution, nothing moves).

use armgate_protocol::client::{Notice, Reply, Request, VALUES};

use super::CommandHandler;
use super::replies::{ik_notice, no_measurement, non_negative, refusal_notice, values_reply};
use crate::command::drives::Drives;
use crate::command::ik;

impl CommandHandler {
    /// `KG`: the joint move to the IK solution of a pose on a branch.
    pub(super) fn ik_goal(
        &mut self,
        req: &Request,
        drives: &(impl Drives + ?Sized),
    ) -> Result<Reply, Notice> {
        let cmd = req.command;
        let v = req.values.map(f64::from);
        let duration = non_negative(v[6]).ok_or(Notice::BadNumber(cmd))?;
        self.ready_to_move(cmd, drives)?;
        let (present, _) = self.controller.measured().ok_or(no_measurement(cmd))?;
        let chain = self.controller.chain();
        let ik = self.controller.ik_config();
        let (goal, branch) =
            ik::goal(chain, ik, &present, &v, req.index).map_err(|e| ik_notice(cmd, e))?;
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

    /// `KS`: an IK solution near the measured joints (mid-range before any measurement).
    pub(super) fn ik_solution(&self, req: &Request) -> Result<Reply, Notice> {
        let v = req.values.map(f64::from);
        let reference = self
            .controller
            .measured()
            .map_or_else(|| self.controller.chain().mid_range(), |(q, _)| q);
        ik::solution(self.controller.chain(), &reference, &v, req.index)
            .map_err(|e| ik_notice(req.command, e))
    }
}
