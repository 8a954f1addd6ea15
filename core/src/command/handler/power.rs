//! The drives' power and calibration: `ON`, `OF` (a controlled stop first if the arm moves) and
//! `RC`.

use armgate_protocol::client::{DriveStatus, Notice, Reply, Request};

use super::CommandHandler;
use super::replies::{bank_values, recalibration_refused, refusal_notice, values_reply};
use crate::command::banks::{BANK_2, BankKey};
use crate::command::drives::Drives;
use crate::motion::StopCause;

impl CommandHandler {
    /// `ON`: starts the drives.
    pub(super) fn power_on(
        &mut self,
        req: &Request,
        drives: &mut (impl Drives + ?Sized),
    ) -> Result<Reply, Notice> {
        self.banks.clear();
        // Already starting (e.g. at power-up): ON asks for what is under way.
        if drives.status() == DriveStatus::Starting {
            return Ok(Reply::null(req.command));
        }
        if drives.start().is_err() {
            return Err(Notice::ArmDidNotStart(drives.status()));
        }
        self.power_off_at = None;
        self.controller.release();
        Ok(Reply::null(req.command))
    }

    /// `OF`: stops the drives.
    pub(super) fn power_off(
        &mut self,
        req: &Request,
        drives: &mut (impl Drives + ?Sized),
    ) -> Result<Reply, Notice> {
        self.banks.clear();
        // Decelerate, then stop the drives (in `tick`); they hold under servo, motors on.
        if self.controller.is_moving() && drives.is_operational() {
            self.controller.stop(StopCause::PowerOff);
            self.power_off_at = Some(self.now + self.stop_within);
            return Ok(Reply::null(req.command));
        }
        if drives.stop().is_err() {
            return Err(Notice::ArmDidNotStop(drives.status()));
        }
        self.controller.release();
        Ok(Reply::null(req.command))
    }

    /// `RC`: declares the present joint angles (bank 2 staged until bank 1 completes them).
    pub(super) fn recalibrate(
        &mut self,
        req: &Request,
        drives: &mut (impl Drives + ?Sized),
    ) -> Result<Reply, Notice> {
        let cmd = req.command;
        let v = req.values.map(f64::from);
        let joints = bank_values(&v, cmd)?;
        if req.index & BANK_2 != 0 {
            self.stage(BankKey::Recalibrate, joints, cmd)?;
            return Ok(values_reply(cmd, joints, BANK_2));
        }
        // Only with the arm off: the measured angles jump (spec §6.8).
        self.in_mode(cmd)?;
        let q = self.complete(BankKey::Recalibrate, joints, cmd)?;
        // Declaring the arm outside its range would make the measured pose illegal
        // and the limiter ease commands back from there (the seed did not check).
        let q = self
            .controller
            .check_joint_goal(&q)
            .map_err(|r| refusal_notice(cmd, r))?;
        drives
            .recalibrate(&q)
            .map_err(|r| recalibration_refused(r, drives.status()))?;
        Ok(Reply::null(cmd))
    }
}
