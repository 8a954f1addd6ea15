//! The Cartesian motion requests: goals (`GL`, `GT`), the move (`BG`), via points (`VP`,
//! `VE`), blend tolerances (`VT`) and the twist stream (`TW`); `VT` and `VE` serve `jT` and
//! `jE` alike.

use armgate_protocol::client::{
    BlendTolerance, Command, Notice, Rejection, Reply, Request, Twist as TwistRequest,
};

use super::CommandHandler;
use super::planning::Slow;
use super::replies::{non_negative, planned_reply, refusal_notice, values_reply};
use crate::command::banks::BANK_2;
use crate::command::drives::Drives;
use crate::math::{self, Frame, Quaternion, Rotation3, Twist, Vector3};
use crate::motion::Refusal;

impl CommandHandler {
    /// `BG`: the move to the stored goal; the reply's f6 is its planned duration (s), so that a
    /// client can size its wait. The line to the goal is checked in slices across ticks: the
    /// answer comes when the check ends ([`lines_checked`](Self::lines_checked)).
    pub(super) fn begin(
        &mut self,
        req: &Request,
        drives: &(impl Drives + ?Sized),
    ) -> Result<Reply, Notice> {
        let cmd = req.command;
        let (goal, duration) = self
            .goal
            .ok_or_else(|| self.missing(cmd, Rejection::NoGoal))?;
        self.ready_to_move(cmd, drives)?;
        let plan = self
            .controller
            .plan_cartesian(goal, duration)
            .map_err(|r| refusal_notice(cmd, r))?;
        self.start_planning(Slow::Lines(cmd, plan));
        // Neither sent nor recorded: the answer comes when the check ends.
        Ok(Reply::null(cmd))
    }

    /// The answer of a `BG` or `VE` whose lines' check ended: the motion started (`result`:
    /// its planned duration, s), or why not.
    pub(super) fn lines_checked(
        &self,
        cmd: Command,
        result: Result<f64, Refusal>,
    ) -> Result<Reply, Notice> {
        match result {
            Ok(_) if cmd == Command::ViaExecute => Ok(Reply::null(cmd)),
            Ok(planned) => Ok(planned_reply(cmd, planned)),
            Err(refusal) => Err(self.start_refused(cmd, refusal)),
        }
    }

    /// The refusal of a motion start: a sequence without via point 0 is missing one.
    fn start_refused(&self, cmd: Command, refusal: Refusal) -> Notice {
        match refusal {
            Refusal::NoGoal if matches!(cmd, Command::ViaExecute | Command::JointExecute) => {
                self.missing(cmd, Rejection::NoViaPoint)
            }
            other => refusal_notice(cmd, other),
        }
    }

    /// `GL`: a goal as position and quaternion.
    pub(super) fn goal_quaternion(&mut self, req: &Request) -> Result<Reply, Notice> {
        let cmd = req.command;
        let [x, y, z, qx, qy, qz, qw] = req.values.map(f64::from);
        let q = Quaternion::new(qx, qy, qz, qw)
            .normalized()
            .ok_or(Notice::BadNumber(cmd))?;
        let goal = Frame::from_parts(Vector3::new(x, y, z).into(), q.to_rotation());
        self.controller
            .check_cartesian_goal(&goal)
            .map_err(|r| refusal_notice(cmd, r))?;
        self.goal = Some((goal, 0.0));
        self.cleared.goal = false;
        let [a, b, c, d] = q.to_array();
        Ok(values_reply(cmd, &[x, y, z, a, b, c, d], 0))
    }

    /// `GT`: a goal as position and roll–pitch–yaw, with a minimum duration.
    pub(super) fn goal_rpy(&mut self, req: &Request) -> Result<Reply, Notice> {
        let cmd = req.command;
        let [x, y, z, roll, pitch, yaw, t] = req.values.map(f64::from);
        let duration = non_negative(t).ok_or(Notice::BadNumber(cmd))?;
        let rotation = Rotation3::from_euler_angles(roll, pitch, yaw);
        let goal = Frame::from_parts(Vector3::new(x, y, z).into(), rotation);
        self.controller
            .check_cartesian_goal(&goal)
            .map_err(|r| refusal_notice(cmd, r))?;
        self.goal = Some((goal, duration));
        self.cleared.goal = false;
        Ok(values_reply(cmd, &[x, y, z, roll, pitch, yaw, duration], 0))
    }

    /// `TW`: a streamed twist; the echo carries how long it holds.
    pub(super) fn twist(
        &mut self,
        req: &Request,
        drives: &(impl Drives + ?Sized),
    ) -> Result<Reply, Notice> {
        let cmd = req.command;
        let twist = TwistRequest::parse(req).map_err(|_| Notice::BadIndex(cmd))?;
        let [vx, vy, vz] = twist.linear.map(f64::from);
        let [wx, wy, wz] = twist.angular.map(f64::from);
        let xi = Twist::new(vx, vy, vz, wx, wy, wz);
        if !xi.iter().all(|v| v.is_finite()) {
            return Err(Notice::BadNumber(cmd));
        }
        self.ready_to_move(cmd, drives)?;
        self.controller
            .stream_twist(xi, twist.frame)
            .map_err(|r| refusal_notice(cmd, r))?;
        let timeout = self.controller.stream_timeout();
        let [vx, vy, vz, wx, wy, wz] = self.controller.stream().within_cartesian_limits(xi).into();
        Ok(values_reply(
            cmd,
            &[vx, vy, vz, wx, wy, wz, timeout],
            req.index,
        ))
    }

    /// `VE` and `jE`: runs the via points of the request's kind. `VE`'s legs are checked in
    /// slices across ticks, as `BG`'s line.
    pub(super) fn run_sequence(
        &mut self,
        req: &Request,
        drives: &(impl Drives + ?Sized),
    ) -> Result<Reply, Notice> {
        let cmd = req.command;
        self.ready_to_move(cmd, drives)?;
        if cmd == Command::ViaExecute {
            let plan = self.controller.plan_cartesian_sequence();
            let plan = plan.map_err(|r| self.start_refused(cmd, r))?;
            self.start_planning(Slow::Lines(cmd, plan));
            return Ok(Reply::null(cmd));
        }
        self.controller
            .start_joint_sequence()
            .map_err(|r| self.start_refused(cmd, r))?;
        Ok(Reply::null(cmd))
    }

    /// `VT` and `jT`: a via point's blend tolerance; the echo is the one in effect.
    pub(super) fn blend_tolerance(&mut self, req: &Request) -> Result<Reply, Notice> {
        let cmd = req.command;
        // The slot is the whole index byte: 20 and above (bank bit included) are
        // refused with ER24, as for VP.
        let tolerance = BlendTolerance::parse(req)
            .ok()
            .and_then(|t| t.tolerance)
            .map(f64::from);
        let slot = usize::from(req.index);
        let in_effect = if cmd == Command::ViaTolerance {
            self.cleared.cartesian_via = false;
            self.controller.set_cartesian_blend(slot, tolerance)
        } else {
            self.cleared.joint_via = false;
            self.controller.set_joint_blend(slot, tolerance)
        }
        .map_err(|r| refusal_notice(cmd, r))?;
        Ok(values_reply(cmd, &[in_effect], req.index))
    }

    /// `VP`: stores a Cartesian via point.
    pub(super) fn via_point(&mut self, req: &Request) -> Result<Reply, Notice> {
        let cmd = req.command;
        if req.index & BANK_2 != 0 {
            return Err(Notice::BadIndex(cmd));
        }
        let slot = usize::from(req.index & !BANK_2);
        let [x, y, z, roll, pitch, yaw, t] = req.values.map(f64::from);
        let duration = non_negative(t).ok_or(Notice::BadNumber(cmd))?;
        let rotation = Rotation3::from_euler_angles(roll, pitch, yaw);
        let pose = Frame::from_parts(Vector3::new(x, y, z).into(), rotation);
        self.controller
            .set_cartesian_via(slot, pose, duration)
            .map_err(|r| refusal_notice(cmd, r))?;
        self.cleared.cartesian_via = false;
        let [r, p, w] = math::rpy(&pose.rotation);
        Ok(values_reply(cmd, &[x, y, z, r, p, w, duration], req.index))
    }
}
