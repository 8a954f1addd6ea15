//! The requests that only read: the measured pose (`PS`) and joints (`jP`), the drives'
//! temperatures (`TM`) and the status reports of `SQ` that are seven floats (among them the
//! body's nearest gap, index 7).

use armgate_protocol::client::branch::BRANCH_INDEX;
use armgate_protocol::client::signed::{IDENTITY_INDEX, SIGNING_INDEX};
use armgate_protocol::client::{
    CAUSE_INDEX, CauseReport, NEAREST_INDEX, NO_JOINT_TEMPERATURE, NearestReport, Notice, Reply,
    Request, STATUS_INDEX,
};

use core::net::SocketAddr;

use super::CommandHandler;
use super::replies::{joint_reply, no_measurement, values_reply};
use crate::command::banks::BANK_2;
use crate::command::drives::Drives;
use crate::command::ik;
use crate::math::Quaternion;
use crate::motion::StopCause;

impl CommandHandler {
    /// `PS`: the measured tool pose, position and quaternion.
    pub(super) fn pose(&self, req: &Request) -> Result<Reply, Notice> {
        let cmd = req.command;
        let (_, pose) = self.controller.measured().ok_or(no_measurement(cmd))?;
        let [x, y, z]: [f64; 3] = pose.translation.vector.into();
        let [a, b, c, d] = Quaternion::from_rotation(&pose.rotation).to_array();
        Ok(values_reply(cmd, &[x, y, z, a, b, c, d], 0))
    }

    /// `jP`: the measured joints.
    pub(super) fn joint_position(&self, req: &Request) -> Result<Reply, Notice> {
        let cmd = req.command;
        let (q, _) = self.controller.measured().ok_or(no_measurement(cmd))?;
        let n = self.controller.chain().dof();
        joint_reply(cmd, &q, req.index & BANK_2 != 0, n, 0.0)
    }

    /// `TM`: the drives' temperatures.
    pub(super) fn temperature(
        &self,
        req: &Request,
        drives: &(impl Drives + ?Sized),
    ) -> Result<Reply, Notice> {
        let t = drives.temperatures();
        let n = self.controller.chain().dof();
        let bank_2 = req.index & BANK_2 != 0;
        joint_reply(req.command, &t, bank_2, n, NO_JOINT_TEMPERATURE)
    }

    /// `SQ` at the indices whose report is seven floats.
    pub(super) fn status_report(
        &self,
        req: &Request,
        drives: &(impl Drives + ?Sized),
    ) -> Result<Reply, Notice> {
        match req.index {
            STATUS_INDEX => Ok(self.status(drives).report().to_reply()),
            CAUSE_INDEX => {
                let (cause, joint) = self.controller.stop_cause();
                // Only the causes a request sets are a client's; the rest are the controller's.
                let by = match (cause, self.stopped_by) {
                    (
                        Some(StopCause::Stop | StopCause::ModeChange | StopCause::PowerOff),
                        Some(SocketAddr::V4(a)),
                    ) => Some(a),
                    _ => None,
                };
                Ok(CauseReport { cause, joint, by }.to_reply())
            }
            SIGNING_INDEX => Ok(self.signing.to_reply()),
            IDENTITY_INDEX => Ok(self.identity.to_reply()),
            BRANCH_INDEX => {
                let present = self.controller.measured().map(|(q, _)| q);
                Ok(ik::present_branch(
                    self.controller.chain(),
                    present.as_ref(),
                ))
            }
            NEAREST_INDEX => {
                let (body, chain) = (self.controller.body(), self.controller.chain());
                let nearest = self.controller.measured().and_then(|(q, _)| {
                    let (gap, hit) = body.nearest_at(chain, &q)?;
                    Some((gap as f32, hit))
                });
                let margin = body.envelope().margin() as f32;
                Ok(NearestReport { nearest, margin }.to_reply())
            }
            _ => Err(Notice::BadIndex(req.command)),
        }
    }
}
