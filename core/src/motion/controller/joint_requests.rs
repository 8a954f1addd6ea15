//! The joint motion requests: a move to a goal (the tool's way checked first), via points and
//! their sequence, and the checks of a joint goal.

use super::{Controller, Mode};
use crate::kinematics::{Joints, KinematicsError, Levers};
use crate::motion::Refusal;
use crate::motion::joint_path::check_joint_path;
use crate::motion::reach::joint_beyond_limit;
use crate::motion::sequence::ViaPoint;

impl Controller {
    /// Moves the joints to `goal` in at least `min_duration` seconds. Joint mode only. The
    /// tool's way is checked first: a move into an exclusion box or out of the workspace is
    /// refused with where (driving out of a box the tool is in stays possible).
    pub fn move_joints(&mut self, goal: &[f64], min_duration: f64) -> Result<f64, Refusal> {
        let goal = self.ready_for_joint_motion(goal, min_duration)?;
        let start = self.joint_generator.setpoint();
        check_joint_path(&self.chain, &self.workspace, &start, &goal, 0.0)?;
        self.body.check_path(&self.chain, &start, &goal)?;
        self.supervisor.clear_cause();
        self.joint_generator.move_to(goal, min_duration.max(0.0))
    }

    /// Stores joint via point `index` (0..20) with the minimum duration of its leg.
    pub fn set_joint_via(
        &mut self,
        index: usize,
        q: &[f64],
        min_duration: f64,
    ) -> Result<(), Refusal> {
        let q = self.valid_joint_goal(q, min_duration)?;
        let via = ViaPoint {
            point: q,
            min_duration: min_duration.max(0.0),
        };
        self.joint_sequence.set(index, via)
    }

    /// Sets the blend tolerance of joint via point `index` (0..20; rad, ≥ 0; `None`: the robot
    /// file's default) and returns the one now in effect there.
    pub fn set_joint_blend(
        &mut self,
        index: usize,
        tolerance: Option<f64>,
    ) -> Result<f64, Refusal> {
        self.joint_sequence.set_blend(index, tolerance)?;
        self.joint_sequence.blend(index)
    }

    /// Empties the joint via-point slots and their blend tolerances; true if any was set.
    pub fn clear_joint_via(&mut self) -> bool {
        self.joint_sequence.clear()
    }

    /// Runs the joint via points 0, 1, … up to the first empty slot. Joint mode only. Every
    /// leg's way is checked first, as for a move, keeping clear of the boxes and the bounds by
    /// as much as a blend at either end may stray from it (its tolerance times
    /// [`Levers::per_joint_distance`]).
    pub fn start_joint_sequence(&mut self) -> Result<(), Refusal> {
        if self.mode != Mode::Joint {
            return Err(Refusal::WrongMode);
        }
        if self.is_moving() {
            return Err(Refusal::Busy);
        }
        let per_joint = Levers::of(&self.chain).per_joint_distance();
        let legs = self.joint_sequence.ready().count();
        let (mut from, mut blend_in) = (self.joint_generator.setpoint(), 0.0_f64);
        for (k, via) in self.joint_sequence.ready().enumerate() {
            // A via point is blended only into a leg after it.
            let blend_out = if k + 1 < legs {
                self.joint_sequence.blend(k).unwrap_or(0.0)
            } else {
                0.0
            };
            let clearance = per_joint * blend_in.max(blend_out);
            check_joint_path(&self.chain, &self.workspace, &from, &via.point, clearance)?;
            self.body.check_path(&self.chain, &from, &via.point)?;
            (from, blend_in) = (via.point, blend_out);
        }
        let first = self.joint_sequence.start()?;
        self.supervisor.clear_cause();
        let then = self.joint_sequence.towards();
        self.joint_generator
            .move_towards(first.point, first.min_duration, then)
            .map(|_| ())
    }

    fn ready_for_joint_motion(&self, goal: &[f64], min_duration: f64) -> Result<Joints, Refusal> {
        if self.mode != Mode::Joint {
            return Err(Refusal::WrongMode);
        }
        let goal = self.valid_joint_goal(goal, min_duration)?;
        if self.is_moving() {
            return Err(Refusal::Busy);
        }
        Ok(goal)
    }

    fn valid_joint_goal(&self, goal: &[f64], min_duration: f64) -> Result<Joints, Refusal> {
        if !min_duration.is_finite() {
            return Err(Refusal::InvalidNumber);
        }
        self.check_joint_goal(goal)
    }

    /// Checks a joint goal without moving: one finite value per joint, within the limits.
    pub fn check_joint_goal(&self, goal: &[f64]) -> Result<Joints, Refusal> {
        let goal = self.chain.check(goal).map_err(|e| match e {
            KinematicsError::WrongJointCount => Refusal::WrongJointCount,
            KinematicsError::NonFiniteJoints => Refusal::InvalidNumber,
        })?;
        if let Some(bound) = joint_beyond_limit(&self.chain, &goal) {
            return Err(Refusal::OutsideJointLimits(bound));
        }
        Ok(goal)
    }
}
