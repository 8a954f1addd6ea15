//! The Cartesian motion requests: a move to a goal (its straight line checked first), shapes,
//! via points and their sequence, and the checks they share.

use super::{Controller, Mode, REACH_TOLERANCE};
use crate::kinematics::Joints;
use crate::math::{self, Frame};
use crate::motion::Refusal;
use crate::motion::reach::{LineCheck, Reach, check_iterations};
use crate::motion::sequence::{VIA_SLOTS, ViaPoint};
use crate::motion::shape::Shape;

/// A Cartesian motion (`BG`'s move, `VE`'s sequence) whose lines are being checked, a few
/// points a tick ([`Controller::continue_plan`]); it starts when the check ends. Fixed size.
#[derive(Clone, Debug)]
pub struct CartesianPlan {
    motion: Planned,
    /// IK iterations left of the request's budget ([`check_iterations`]).
    iterations_left: u32,
    /// The line being checked: none once all are (or if the robot file turned the check off).
    line: Option<LineCheck>,
}

/// What starts when a plan's check ends.
#[derive(Clone, Copy, Debug)]
enum Planned {
    /// A move to `goal`, planned to last at least `min_duration` (s; the check's once done).
    Move { goal: Frame, min_duration: f64 },
    /// The via-point sequence: the leg being checked, the durations of those checked.
    Sequence {
        leg: usize,
        durations: [f64; VIA_SLOTS],
    },
}

impl Controller {
    /// Moves the tool to `goal` (base frame) in at least `min_duration` seconds (negative: as
    /// fast as the limits allow). Cartesian mode only.
    /// The straight line to the goal is checked first (docs/protocol.md): a move the arm cannot
    /// follow is refused with where and why. In one call: the cycle runs the check in slices
    /// ([`plan_cartesian`](Self::plan_cartesian)). Returns the planned duration (s).
    pub fn move_cartesian(&mut self, goal: Frame, min_duration: f64) -> Result<f64, Refusal> {
        let mut plan = self.plan_cartesian(goal, min_duration)?;
        self.finish_plan(&mut plan)
    }

    /// A move to `goal` as [`move_cartesian`](Self::move_cartesian), its line yet to be
    /// checked by [`continue_plan`](Self::continue_plan): what refuses it at once is refused
    /// here (wrong mode, a goal outside the workspace, moving, a line through a box).
    pub fn plan_cartesian(&self, goal: Frame, min_duration: f64) -> Result<CartesianPlan, Refusal> {
        self.ready_for_cartesian_motion(&goal, min_duration)?;
        let min_duration = min_duration.max(0.0);
        let mut plan = self.plan(Planned::Move { goal, min_duration });
        if let Some(reach) = self.reach() {
            let (start, seed) = self.cartesian_start();
            plan.line = Some(reach.begin_line(&start, &goal, &seed, min_duration)?);
        }
        Ok(plan)
    }

    /// The Cartesian via-point sequence as
    /// [`start_cartesian_sequence`](Self::start_cartesian_sequence), its legs yet to be
    /// checked by [`continue_plan`](Self::continue_plan).
    pub fn plan_cartesian_sequence(&self) -> Result<CartesianPlan, Refusal> {
        self.ready_for_cartesian_motion(&self.cartesian_generator.setpoint(), 0.0)?;
        let durations = [0.0; VIA_SLOTS];
        let mut plan = self.plan(Planned::Sequence { leg: 0, durations });
        if let (Some(reach), Some(via)) = (self.reach(), self.cartesian_sequence.ready().next()) {
            let (start, seed) = self.cartesian_start();
            plan.line = Some(reach.begin_line(&start, &via.point, &seed, via.min_duration)?);
        }
        Ok(plan)
    }

    /// A plan of `motion` with the request's whole IK budget and no line begun.
    fn plan(&self, motion: Planned) -> CartesianPlan {
        CartesianPlan {
            motion,
            iterations_left: check_iterations(self.period),
            line: None,
        }
    }

    /// Checks `plan` on while `work` lasts (a slice of the check, a few points of its lines:
    /// each point [`POINT_WORK`](crate::motion::POINT_WORK) and one per Newton iteration of its
    /// solve); once the check has ended, starts the motion if it passed and the arm may still
    /// start it (the check may have taken ticks) and returns its planned duration (s; a
    /// sequence's first leg's), or why not. `None` while the check goes on.
    pub fn continue_plan(
        &mut self,
        plan: &mut CartesianPlan,
        mut work: usize,
    ) -> Option<Result<f64, Refusal>> {
        if let Some(mut reach) = self.reach() {
            reach.iterations_left = plan.iterations_left;
            // A line a pass, the sequence's legs at most.
            for _ in 0..=VIA_SLOTS {
                let Some(line) = plan.line.as_mut() else {
                    break;
                };
                let checked = reach.continue_line(line, &mut work);
                plan.iterations_left = reach.iterations_left;
                let checked = match checked? {
                    Ok(checked) => checked,
                    Err(refusal) => return Some(Err(refusal)),
                };
                plan.line = None;
                match &mut plan.motion {
                    Planned::Move { min_duration, .. } => *min_duration = checked.duration,
                    Planned::Sequence { leg, durations } => {
                        if let Some(duration) = durations.get_mut(*leg) {
                            *duration = checked.duration;
                        }
                        let from = self.cartesian_sequence.ready().nth(*leg);
                        *leg = leg.saturating_add(1);
                        if let (Some(from), Some(to)) =
                            (from, self.cartesian_sequence.ready().nth(*leg))
                        {
                            let q = &checked.q;
                            match reach.begin_line(&from.point, &to.point, q, to.min_duration) {
                                Ok(line) => plan.line = Some(line),
                                Err(refusal) => return Some(Err(refusal)),
                            }
                        }
                    }
                }
            }
        }
        Some(self.start_plan(&plan.motion))
    }

    /// Runs `plan`'s check to its end and starts its motion (the one-call requests).
    fn finish_plan(&mut self, plan: &mut CartesianPlan) -> Result<f64, Refusal> {
        // Never `None`: with every point at once the check ends.
        self.continue_plan(plan, usize::MAX)
            .unwrap_or(Err(Refusal::Busy))
    }

    /// Starts a checked motion, if the arm may still start it.
    fn start_plan(&mut self, motion: &Planned) -> Result<f64, Refusal> {
        match motion {
            Planned::Move { goal, min_duration } => {
                self.ready_for_cartesian_motion(goal, *min_duration)?;
                self.supervisor.clear_cause();
                self.cartesian_generator.move_to(*goal, *min_duration)
            }
            Planned::Sequence { durations, .. } => {
                self.ready_for_cartesian_motion(&self.cartesian_generator.setpoint(), 0.0)?;
                let first = self.cartesian_sequence.start_planned(durations)?;
                self.supervisor.clear_cause();
                let then = self.cartesian_sequence.towards();
                self.cartesian_generator
                    .move_towards(first.point, first.min_duration, then)
            }
        }
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
    /// as the check says. In one call: the cycle runs the check in slices
    /// ([`plan_cartesian_sequence`](Self::plan_cartesian_sequence)).
    pub fn start_cartesian_sequence(&mut self) -> Result<(), Refusal> {
        let mut plan = self.plan_cartesian_sequence()?;
        self.finish_plan(&mut plan).map(|_| ())
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
