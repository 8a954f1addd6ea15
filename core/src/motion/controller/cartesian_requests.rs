//! The Cartesian motion requests: a move to a goal (its straight line checked first), shapes,
//! via points and their sequence, and the checks they share.

use super::{Controller, Mode, REACH_TOLERANCE};
use crate::kinematics::Joints;
use crate::math::{self, Frame};
use crate::motion::Refusal;
use crate::motion::reach::{Reach, check_iterations};
use crate::motion::sequence::{VIA_SLOTS, ViaPoint};
use crate::motion::shape::Shape;

impl Controller {
    /// Moves the tool to `goal` (base frame) in at least `min_duration` seconds (negative: as
    /// fast as the limits allow). Cartesian mode only.
    /// The straight line to the goal is checked first (docs/protocol.md): a move the arm cannot
    /// follow is refused with where and why.
    pub fn move_cartesian(&mut self, goal: Frame, min_duration: f64) -> Result<f64, Refusal> {
        self.ready_for_cartesian_motion(&goal, min_duration)?;
        let mut min_duration = min_duration.max(0.0);
        if let Some(mut reach) = self.reach() {
            let (start, seed) = self.cartesian_start();
            min_duration = reach.line(&start, &goal, &seed, min_duration)?.duration;
        }
        self.supervisor.clear_cause();
        self.cartesian_generator.move_to(goal, min_duration)
    }

    /// The pose a Cartesian motion starts from and the joints commanded there.
    fn cartesian_start(&self) -> (Frame, Joints) {
        let seed = self
            .command
            .or(self.measured.map(|(q, _)| q))
            .unwrap_or_else(|| self.chain.mid_range());
        (self.cartesian_generator.setpoint(), seed)
    }

    /// The up-front check of Cartesian lines (`None` if the robot file turned it off).
    fn reach(&self) -> Option<Reach<'_>> {
        self.ik.check_lines.then_some(Reach {
            chain: &self.chain,
            ik: &self.ik,
            workspace: &self.workspace,
            tolerance: REACH_TOLERANCE,
            iterations_left: check_iterations(self.period),
            speed: &self.cartesian_speed,
            acceleration: &self.cartesian_acceleration,
            max_rate: &self.max_rate,
            max_acceleration: &self.max_acceleration,
            body: &self.body,
        })
    }

    /// Runs a circle or sinusoid from the current set-point. Cartesian mode only.
    pub fn start_shape(&mut self, shape: Shape) -> Result<(), Refusal> {
        self.ready_for_cartesian_motion(&self.cartesian_generator.setpoint(), 0.0)?;
        self.supervisor.clear_cause();
        self.cartesian_generator.start_shape(shape)
    }

    /// Asks a running shape to end where it started (end of revolution / centre crossing).
    pub fn finish_shape(&mut self) -> Result<(), Refusal> {
        if self.cartesian_generator.finish_shape() {
            Ok(())
        } else {
            Err(Refusal::NoGoal)
        }
    }

    /// Stores Cartesian via point `index` (0..20) with the minimum duration of its leg.
    pub fn set_cartesian_via(
        &mut self,
        index: usize,
        pose: Frame,
        min_duration: f64,
    ) -> Result<(), Refusal> {
        if !min_duration.is_finite() {
            return Err(Refusal::InvalidNumber);
        }
        self.check_cartesian_goal(&pose)?;
        let via = ViaPoint {
            point: pose,
            min_duration: min_duration.max(0.0),
        };
        self.cartesian_sequence.set(index, via)
    }

    /// Sets the blend tolerance of Cartesian via point `index` (0..20; m + rad, ≥ 0; `None`:
    /// the robot file's default) and returns the one now in effect there.
    pub fn set_cartesian_blend(
        &mut self,
        index: usize,
        tolerance: Option<f64>,
    ) -> Result<f64, Refusal> {
        self.cartesian_sequence.set_blend(index, tolerance)?;
        self.cartesian_sequence.blend(index)
    }

    /// Empties the Cartesian via-point slots and their blend tolerances; true if any was set.
    pub fn clear_cartesian_via(&mut self) -> bool {
        self.cartesian_sequence.clear()
    }

    /// Runs the Cartesian via points 0, 1, … up to the first empty slot. Cartesian mode only.
    /// Every leg's straight line is checked first, as for a move, and planned to last as long
    /// as the check says.
    pub fn start_cartesian_sequence(&mut self) -> Result<(), Refusal> {
        self.ready_for_cartesian_motion(&self.cartesian_generator.setpoint(), 0.0)?;
        let mut durations = [0.0; VIA_SLOTS];
        if let Some(mut reach) = self.reach() {
            let (mut from, mut q) = self.cartesian_start();
            for (via, duration) in self.cartesian_sequence.ready().zip(durations.iter_mut()) {
                let checked = reach.line(&from, &via.point, &q, via.min_duration)?;
                (q, *duration) = (checked.q, checked.duration);
                from = via.point;
            }
        }
        let first = self.cartesian_sequence.start_planned(&durations)?;
        self.supervisor.clear_cause();
        let then = self.cartesian_sequence.towards();
        self.cartesian_generator
            .move_towards(first.point, first.min_duration, then)
            .map(|_| ())
    }

    fn ready_for_cartesian_motion(&self, goal: &Frame, min_duration: f64) -> Result<(), Refusal> {
        if self.mode != Mode::Cartesian {
            return Err(Refusal::WrongMode);
        }
        if !min_duration.is_finite() {
            return Err(Refusal::InvalidNumber);
        }
        self.check_cartesian_goal(goal)?;
        if self.is_moving() {
            return Err(Refusal::Busy);
        }
        let arm_inside = self
            .measured
            .is_some_and(|(_, pose)| self.workspace.allows(&pose.translation.vector));
        if !arm_inside {
            return Err(Refusal::ArmOutsideWorkspace);
        }
        Ok(())
    }

    /// Checks a Cartesian goal without moving: finite, and its position inside the workspace.
    pub fn check_cartesian_goal(&self, goal: &Frame) -> Result<(), Refusal> {
        if !math::is_finite(goal) {
            return Err(Refusal::InvalidNumber);
        }
        if !self.workspace.allows(&goal.translation.vector) {
            return Err(Refusal::OutsideWorkspace);
        }
        Ok(())
    }
}
