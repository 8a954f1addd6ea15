//! The joint motion requests: the goal (`jG`) and the move (`jB`), via points (`jV`; `jE` runs
//! them with `VE`, in cartesian.rs) and the joint-rate stream (`jW`), each staged in two banks
//! on an arm with more than six joints.

use armgate_protocol::client::{JointRates, Notice, Rejection, Reply, Request};

use super::CommandHandler;
use super::replies::{bank_values, non_negative, planned_reply, refusal_notice, values_reply};
use crate::command::banks::{BANK_2, BANK_LEN, BankKey};
use crate::command::drives::Drives;

impl CommandHandler {
    /// `jB`: the move to the stored joint goal.
    pub(super) fn joint_begin(
        &mut self,
        req: &Request,
        drives: &(impl Drives + ?Sized),
    ) -> Result<Reply, Notice> {
        let cmd = req.command;
        let goal = self
            .joint_goal
            .ok_or_else(|| self.missing(cmd, Rejection::NoGoal))?;
        self.ready_to_move(cmd, drives)?;
        let planned = self
            .controller
            .move_joints(&goal, 0.0)
            .map_err(|r| refusal_notice(cmd, r))?;
        Ok(planned_reply(cmd, planned))
    }

    /// `jG`: stores the joint goal (bank 2 staged until bank 1 completes it).
    pub(super) fn joint_goal(&mut self, req: &Request) -> Result<Reply, Notice> {
        let cmd = req.command;
        let v = req.values.map(f64::from);
        let joints = bank_values(&v, cmd)?;
        if req.index & BANK_2 != 0 {
            self.stage(BankKey::Goal, joints, cmd)?;
        } else {
            let q = self.complete(BankKey::Goal, joints, cmd)?;
            let goal = self.controller.check_joint_goal(&q);
            self.joint_goal = Some(goal.map_err(|r| refusal_notice(cmd, r))?);
            self.cleared.joint_goal = false;
        }
        // The seed's f6 was stale (spec §9 item 9).
        Ok(values_reply(cmd, joints, req.index & BANK_2))
    }

    /// `jW`: streamed joint rates; the echo carries how long they hold.
    pub(super) fn joint_velocity(
        &mut self,
        req: &Request,
        drives: &(impl Drives + ?Sized),
    ) -> Result<Reply, Notice> {
        let cmd = req.command;
        let v = req.values.map(f64::from);
        let rates = JointRates::parse(req).map_err(|_| Notice::BadIndex(cmd))?;
        let joints = bank_values(&v, cmd)?;
        self.ready_to_move(cmd, drives)?;
        if rates.bank_2 {
            self.stage(BankKey::Rates, joints, cmd)?;
        } else {
            let q = self.complete(BankKey::Rates, joints, cmd)?;
            self.controller
                .stream_joint_rates(&q)
                .map_err(|r| refusal_notice(cmd, r))?;
        }
        // The echo: the rates as sent, and in f6 how long they hold.
        let mut values = v;
        values[BANK_LEN] = self.controller.stream_timeout();
        Ok(values_reply(cmd, &values, req.index))
    }

    /// `jV`: stores a joint via point.
    pub(super) fn joint_via(&mut self, req: &Request) -> Result<Reply, Notice> {
        let cmd = req.command;
        let v = req.values.map(f64::from);
        let slot = usize::from(req.index & !BANK_2);
        let joints = bank_values(&v, cmd)?;
        let duration = non_negative(v[6]).ok_or(Notice::BadNumber(cmd))?;
        if req.index & BANK_2 != 0 {
            self.stage(BankKey::Via(slot), joints, cmd)?;
        } else {
            let q = self.complete(BankKey::Via(slot), joints, cmd)?;
            self.controller
                .set_joint_via(slot, &q, duration)
                .map_err(|r| refusal_notice(cmd, r))?;
            self.cleared.joint_via = false;
        }
        // The echo: the joints as sent (`joints` is `v`'s first BANK_LEN values), then
        // the clamped duration. No slice copy that could panic on a length mismatch.
        let mut values = v;
        values[BANK_LEN] = duration;
        Ok(values_reply(cmd, &values, req.index))
    }
}
