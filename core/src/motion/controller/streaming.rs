//! The velocity stream inside the controller (`TW`, `jW`): its requests, and its tick in
//! either mode.

use super::{Controller, Mode};
use crate::kinematics::{Joints, KinematicsError};
use crate::math::Twist;
use crate::motion::Events;
use crate::motion::Refusal;
use crate::motion::supervisor::{Along, StopCause};
use crate::motion::velocity_stream::{StreamCommand, StreamStep};
use armgate_protocol::client::{Hold, JointBound, PathPoint, TwistFrame};

impl Controller {
    /// Either mode, while a velocity stream runs: its set-point from the last command.
    pub(super) fn stream_tick(&mut self, q_m: &Joints, events: &mut Events) -> StreamStep {
        let q = self.command.unwrap_or(*q_m);
        let step = self
            .stream
            .step(&self.chain, (&self.workspace, &self.body), &q);
        events.workspace_limit |= step.workspace_limit;
        events.hold = match step.held_joint {
            Some((i, upper)) => {
                let limits = if upper {
                    self.chain.max()
                } else {
                    self.chain.min()
                };
                let limit = limits.get(i).copied().unwrap_or(0.0);
                let bound = JointBound::new(i, upper, limit, PathPoint::Goal);
                Some(Hold::JointLimit(bound))
            }
            None => match step.contact {
                Some(hit) => Some(Hold::Contact(hit)),
                None if step.workspace_limit => Some(Hold::Workspace),
                None => None,
            },
        };
        self.supervisor.hold(events.hold);
        step
    }

    /// Streams a tool twist `[vx, vy, vz, ωx, ωy, ωz]` (m/s, rad/s) in `frame`, valid for
    /// [`TIMEOUT_PERIODS`](super::TIMEOUT_PERIODS) ticks from the next one. Cartesian mode
    /// only; refused while a move or sequence runs.
    pub fn stream_twist(&mut self, twist: Twist, frame: TwistFrame) -> Result<(), Refusal> {
        if !twist.iter().all(|v| v.is_finite()) {
            return Err(Refusal::InvalidNumber);
        }
        self.start_stream(Mode::Cartesian, StreamCommand::Twist(twist, frame))
    }

    /// Streams joint rates (rad/s, or m/s for prismatic joints), one per joint, valid for
    /// [`TIMEOUT_PERIODS`](super::TIMEOUT_PERIODS) ticks from the next one. Joint mode only;
    /// refused while a move or sequence runs.
    pub fn stream_joint_rates(&mut self, rates: &[f64]) -> Result<(), Refusal> {
        let rates = self.chain.check(rates).map_err(|e| match e {
            KinematicsError::WrongJointCount => Refusal::WrongJointCount,
            KinematicsError::NonFiniteJoints => Refusal::InvalidNumber,
        })?;
        self.start_stream(Mode::Joint, StreamCommand::JointRates(rates))
    }

    /// Hands a checked command to the stream if it may run in `mode` now.
    fn start_stream(&mut self, mode: Mode, command: StreamCommand) -> Result<(), Refusal> {
        self.ready_for_stream(mode, command.is_zero())?;
        self.supervisor.clear_cause();
        self.stream.command(command);
        Ok(())
    }

    /// A stream may start, or resume while its own stop (`ST`, its timeout) is under way: it
    /// then takes over from the velocity commanded last, within the same limits. After a stop
    /// that latched, only a `zero` command may (it re-arms the stream: the holder asks for
    /// rest on purpose), so that a stream still being sent cannot undo the stop.
    fn ready_for_stream(&mut self, mode: Mode, zero: bool) -> Result<(), Refusal> {
        if self.mode != mode {
            return Err(Refusal::WrongMode);
        }
        if self.measured.is_none() {
            return Err(Refusal::NotReady);
        }
        if let Some(cause) = self.supervisor.latch().filter(|_| !zero) {
            return Err(Refusal::Stopped(cause));
        }
        let stream_stopping = self.supervisor.stopping().is_some_and(|stop| {
            matches!(stop.along, Along::Joints(_))
                && matches!(stop.cause, StopCause::Stop | StopCause::StreamTimeout)
        });
        if stream_stopping {
            self.supervisor.finish();
            self.stream
                .resume(self.supervisor.velocity(), self.supervisor.acceleration());
            return Ok(());
        }
        if self.is_moving() && !self.stream.is_active() {
            return Err(Refusal::Busy);
        }
        Ok(())
    }
}
