//! The control step: one deterministic tick of the whole motion pipeline (spec §1.4).

use super::cartesian_generator::CartesianGenerator;
use super::fixed_point::FixedPoint;
use super::joint_generator::JointGenerator;
use super::joint_limiter::JointLimiter;
use super::reach::{Reach, check_iterations, joint_beyond_limit};
use super::sequence::{Sequence, SequenceStep, Tolerances, ViaPoint};
use super::shape::Shape;
use super::velocity_stream::{StreamCommand, StreamStep, VelocityStream};
use super::workspace::Workspace;
use super::{Events, Refusal};
use crate::config::{IkConfig, ValidRobot};
use crate::kinematics::{Chain, Joints, KinematicsError};
use crate::math::{self, Frame, Twist};
use armgate_protocol::client::{Motion, TwistFrame};

/// Below this pose error (m and rad, the seed's IK tolerance) a Cartesian set-point counts as
/// reached; above it the tick raises [`Events::ik_divergence`] and holds the last command. This
/// is stricter than the seed's guard (spec §3.5), which still commanded a non-converged solution
/// unless it was worse than the current pose by 1e-4: such best-effort poses trade position for
/// orientation and wander away from an unreachable goal.
const REACH_TOLERANCE: f64 = 1e-6;
/// The seed's via-point tolerances (spec §4.4).
const CARTESIAN_TOLERANCES: Tolerances = Tolerances {
    fine: 0.002,
    coarse: 0.1,
};
const JOINT_TOLERANCES: Tolerances = Tolerances {
    fine: 0.001,
    coarse: 0.05,
};
/// Attempts per tick at a smaller step when the full one is too fast for the joints.
const SLOWDOWN_ATTEMPTS: usize = 4;
/// Below this fraction of real time a motion counts as stalled rather than slowed down.
const MIN_TIME_SCALE: f64 = 0.01;
/// A Cartesian motion that cannot advance for this long (s) is aborted.
pub const STALL_TIME: f64 = 0.5;

/// How a Cartesian set-point can be tracked this tick.
enum Tracking {
    /// Reached within the tolerance and the rate limits.
    Reached(Joints),
    /// Reached, but some joint would exceed its rate limit by this factor.
    TooFast(f64),
    /// Not reached within the tolerance.
    Unreachable,
}

/// The control mode: a rule of the wire (`CM`), defined once in the protocol crate.
pub use armgate_protocol::client::Mode;

/// What one tick produced.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepOutput {
    /// The tick's time, as given to [`Controller::step`] (s).
    pub time: f64,
    /// The joint command for the drives; `None` means hold the last one (mode off).
    pub command: Option<Joints>,
    /// What happened this tick.
    pub events: Events,
    /// FK of the measured joints.
    pub measured_pose: Frame,
    /// The Cartesian set-point given to the IK this tick (Cartesian mode only).
    pub setpoint: Option<Frame>,
}

/// The whole motion pipeline of one arm: generators, via-point sequences, workspace check, IK,
/// mode switch and joint limiter.
///
/// [`step`](Self::step) runs one tick; the motion requests are methods that either start
/// something or say why not. Nothing here reads a clock: time is an argument.
///
/// Mode transitions never emit a stale or jumping set-point, by construction: on every
/// transition the newly active generator is made to hold exactly the last joint command (the
/// measured joints if the arm was off), the Cartesian one at its FK, and the IK is a pure
/// function seeded from the last command, with no output of its own that could go stale. The
/// first command after a transition therefore equals the last one before it. (The seed needed
/// a two-cycle hold for this and missed a stale IK output on entering Cartesian mode, spec §9
/// item 28.)
#[derive(Clone, Debug)]
pub struct Controller {
    chain: Chain,
    ik: IkConfig,
    limiter: JointLimiter,
    workspace: Workspace,
    mode: Mode,
    joint_generator: JointGenerator,
    cartesian_generator: CartesianGenerator,
    joint_sequence: Sequence<Joints>,
    cartesian_sequence: Sequence<Frame>,
    /// Twist and joint-rate streaming (TW, jW).
    stream: VelocityStream,
    /// The last joint command sent (none while off).
    command: Option<Joints>,
    /// The last measurement and its FK.
    measured: Option<(Joints, Frame)>,
    /// Control period (s): each tick advances the motion by at most this much motion time.
    period: f64,
    /// Consecutive ticks in which a Cartesian motion could not advance.
    stalled_ticks: u32,
    /// The last tracking solve that returned its seed: a holding arm's solve, not repeated.
    fixed_point: FixedPoint,
}

impl Controller {
    /// A controller for a validated robot description, in mode off.
    pub fn new(config: &ValidRobot) -> Self {
        let n = config.dof();
        let v_max = config.per_joint(|j| j.max_velocity);
        let a_max = config.per_joint(|j| j.max_acceleration);
        let j_max = config.joint_jerk_limits();
        let cartesian_j_max = config.cartesian_jerk_limits();
        let cartesian = &config.cartesian;
        Self {
            chain: Chain::new(config),
            ik: config.ik,
            limiter: JointLimiter::new(config),
            workspace: Workspace::new(&config.workspace),
            mode: Mode::Off,
            joint_generator: JointGenerator::new(Joints::zeros(n), v_max, a_max)
                .with_jerk_limits(j_max),
            cartesian_generator: CartesianGenerator::new(
                Frame::identity(),
                cartesian.max_velocity,
                cartesian.max_acceleration,
            )
            .with_jerk_limits(cartesian_j_max),
            joint_sequence: Sequence::new(JOINT_TOLERANCES, config.blend.joint),
            cartesian_sequence: Sequence::new(CARTESIAN_TOLERANCES, config.blend.cartesian),
            stream: VelocityStream::new(config),
            command: None,
            measured: None,
            period: config.control_period,
            stalled_ticks: 0,
            fixed_point: FixedPoint::default(),
        }
    }

    /// One control tick at time `now` (s) with the measured joints: FK, via-point sequence,
    /// generator, workspace check, IK, mode switch, joint limiter — in that order.
    ///
    /// Every command becomes a set-point that the drives execute over exactly one control
    /// period, so each step advances motion time by one period, whatever `now` says: a late
    /// tick never makes the arm jump to catch up. `now` only stamps the output.
    pub fn step(&mut self, now: f64, measured: &[f64]) -> Result<StepOutput, KinematicsError> {
        let q_m = self.chain.check(measured)?;
        let f_m = self.chain.pose(&q_m);
        // Written in place: `self.measured = Some((q_m, f_m))` built the 168-byte pair and
        // copied it twice on the Cortex-M7 (≈ 450 instructions a tick in qemu-bench).
        match &mut self.measured {
            Some((q, f)) => (*q, *f) = (q_m, f_m),
            none => *none = Some((q_m, f_m)),
        }
        let mut events = Events {
            workspace_limit: !self.workspace.allows(&f_m.translation.vector),
            ..Events::default()
        };
        let mut stream_finished = false;
        let (request, setpoint) = match self.mode {
            Mode::Off => (None, None),
            Mode::Joint | Mode::Cartesian if self.stream.is_active() => {
                let step = self.stream_tick(&q_m, &mut events);
                stream_finished = step.finished;
                let setpoint = (self.mode == Mode::Cartesian).then_some(step.pose);
                (Some(step.q), setpoint)
            }
            Mode::Joint => (Some(self.joint_tick(&q_m, &mut events)), None),
            Mode::Cartesian => {
                let (q, sp) = self.cartesian_tick(&q_m, &f_m, &mut events);
                (Some(q), Some(sp))
            }
        };
        let command = request.map(|r| {
            let limited = self
                .limiter
                .limit(&r, self.command.as_ref().unwrap_or(&q_m));
            events.joint_limit = limited.position_clamped;
            events.rate_limit = limited.rate_clamped;
            limited.q
        });
        if command.is_some() {
            self.command = command;
        }
        if stream_finished {
            // The generators take over where the stream came to rest.
            self.hold(q_m);
        }
        Ok(StepOutput {
            time: now,
            command,
            events,
            measured_pose: f_m,
            setpoint,
        })
    }

    /// Either mode, while a velocity stream runs: its set-point from the last command.
    fn stream_tick(&mut self, q_m: &Joints, events: &mut Events) -> StreamStep {
        let q = self.command.unwrap_or(*q_m);
        let step = self.stream.step(&self.chain, &self.workspace, &q);
        events.workspace_limit |= step.workspace_limit;
        events.joint_limit |= step.joint_limit;
        step
    }

    /// Joint mode: sequence, then generator.
    fn joint_tick(&mut self, q_m: &Joints, events: &mut Events) -> Joints {
        let leg_done = !self.joint_generator.is_moving();
        let step = self
            .joint_sequence
            .poll(leg_done, |p| joint_distance(p, q_m));
        if let SequenceStep::MoveTo(via) = step {
            // The generator is idle, so the move cannot be refused.
            let then = self.joint_sequence.towards();
            let _ = self
                .joint_generator
                .move_towards(via.point, via.min_duration, then);
        }
        note_sequence(step, events);
        // A blend stays within the joint limits: its path lies within the tolerance of the via
        // point, which is kept below the via point's distance to the nearest limit.
        let (chain, generator, period) = (&self.chain, &mut self.joint_generator, self.period);
        self.joint_sequence.hand_over(
            generator.accepts_blend(),
            |q| limit_margin(chain, q),
            |via, tolerance, then| {
                generator.blend_into(via.point, via.min_duration, tolerance, then, period)
            },
        );
        let (setpoint, finished) = self.joint_generator.advance(self.period);
        events.motion_finished |= finished && !self.joint_sequence.is_running();
        setpoint
    }

    /// Cartesian mode: sequence, generator, workspace check, IK.
    ///
    /// The generator advances by one period of motion time, or by less when the IK solution of
    /// the full step would need a joint to move faster than its rate limit: the path stays exact
    /// and the motion slows down (the seed enforced no rate in position mode, spec §9 item 27).
    /// A set-point that cannot be tracked even at a much smaller step (out of reach, or at a
    /// singularity) holds the arm and raises [`Events::ik_divergence`]; a motion stalled like
    /// this for [`STALL_TIME`] is aborted.
    fn cartesian_tick(
        &mut self,
        q_m: &Joints,
        f_m: &Frame,
        events: &mut Events,
    ) -> (Joints, Frame) {
        let leg_done = !self.cartesian_generator.is_moving();
        let step = self
            .cartesian_sequence
            .poll(leg_done, |p| math::dist(p, f_m));
        if let SequenceStep::MoveTo(via) = step {
            let then = self.cartesian_sequence.towards();
            let _ = self
                .cartesian_generator
                .move_towards(via.point, via.min_duration, then);
        }
        note_sequence(step, events);
        // A blend's set-points stay within the tolerance of the via point, kept below its
        // distance to the workspace's edges and boxes.
        let (workspace, generator, period) =
            (&self.workspace, &mut self.cartesian_generator, self.period);
        self.cartesian_sequence.hand_over(
            generator.accepts_blend(),
            |pose| workspace.margin(&pose.translation.vector),
            |via, tolerance, then| {
                generator.blend_into(via.point, via.min_duration, tolerance, then, period)
            },
        );

        let seed = self.command.unwrap_or(*q_m);
        let t0 = self.cartesian_generator.elapsed();
        let mut scale = 1.0;
        for _ in 0..SLOWDOWN_ATTEMPTS {
            let t = t0 + self.period * scale;
            let sample = self.cartesian_generator.sample(t);
            let (setpoint, finished) = sample;
            if events.workspace_limit || !self.workspace.allows(&setpoint.translation.vector) {
                // An illegal set-point never reaches the IK: abort and hold the commanded pose.
                events.workspace_limit = true;
                return (seed, self.abort_cartesian_motion(&seed, f_m, events));
            }
            match self.track(&setpoint, &seed) {
                Tracking::Reached(q) => {
                    self.stalled_ticks = 0;
                    self.cartesian_generator.commit(t, sample);
                    events.motion_finished |= finished && !self.cartesian_sequence.is_running();
                    return (q, setpoint);
                }
                Tracking::TooFast(ratio) if scale / ratio >= MIN_TIME_SCALE => {
                    // Joint steps grow about linearly with the step along the path.
                    scale /= ratio * 1.05;
                }
                Tracking::TooFast(_) | Tracking::Unreachable => break,
            }
        }
        events.ik_divergence = true;
        self.stalled_ticks = self.stalled_ticks.saturating_add(1);
        let stalled = f64::from(self.stalled_ticks) * self.period >= STALL_TIME;
        if !self.cartesian_generator.is_moving() || stalled {
            return (seed, self.abort_cartesian_motion(&seed, f_m, events));
        }
        (seed, self.cartesian_generator.setpoint())
    }

    /// Tracking IK from `seed` to `setpoint`, checked against the reach tolerance and the
    /// joints' rate limits. A solve known to return its seed is not repeated ([`FixedPoint`]).
    fn track(&mut self, setpoint: &Frame, seed: &Joints) -> Tracking {
        if self.fixed_point.holds(setpoint, seed) {
            return Tracking::Reached(*seed);
        }
        let Ok(result) = self.chain.solve_tracking(setpoint, seed, &self.ik) else {
            return Tracking::Unreachable;
        };
        let s = result.solution();
        // Written so that a NaN error (or solution) fails: it is not reached.
        let reached = s.position_error <= REACH_TOLERANCE
            && s.orientation_error <= REACH_TOLERANCE
            && s.q.is_finite();
        if !reached {
            return Tracking::Unreachable;
        }
        match self.limiter.rate_ratio(&s.q, seed) {
            ratio if ratio <= 1.0 => {
                self.fixed_point.note(setpoint, seed, &s.q);
                Tracking::Reached(s.q)
            }
            ratio => Tracking::TooFast(ratio),
        }
    }

    /// Stops the Cartesian motion (and its sequence) and holds the commanded pose.
    fn abort_cartesian_motion(&mut self, seed: &Joints, f_m: &Frame, events: &mut Events) -> Frame {
        self.stalled_ticks = 0;
        events.sequence_aborted |= self.cartesian_sequence.is_running();
        self.cartesian_sequence.halt();
        let hold = self.chain.forward(seed).unwrap_or(*f_m);
        self.cartesian_generator.hold(hold);
        hold
    }

    /// Switches the control mode. The newly active generator holds the last command (or the
    /// measured joints when coming from off), so the switch itself never moves the arm.
    /// Selecting the current mode again stops any motion.
    pub fn set_mode(&mut self, mode: Mode) -> Result<(), Refusal> {
        let (q_m, _) = self.measured.ok_or(Refusal::NotReady)?;
        self.mode = mode;
        self.stream.halt();
        self.hold(q_m);
        if mode == Mode::Off {
            self.command = None;
        }
        Ok(())
    }

    /// Forgets the last command and holds the measured position: for while the drives do not
    /// take commands (starting, stopped, faulted), so that when they do, the first command is
    /// where the arm actually is rather than a stale set-point (the seed reset its generator
    /// after start-up for the same reason). Stops every motion and sequence.
    pub fn release(&mut self) {
        self.command = None;
        self.stream.halt();
        self.stop();
    }

    /// Stops every motion and sequence; the arm holds its commanded position. A velocity
    /// stream instead ramps to rest within the acceleration limits.
    pub fn stop(&mut self) {
        self.stream.ramp_to_rest();
        if let Some((q_m, _)) = self.measured {
            self.hold(q_m);
        }
    }

    /// Streams a tool twist `[vx, vy, vz, ωx, ωy, ωz]` (m/s, rad/s) in `frame`, valid for
    /// [`TIMEOUT_PERIODS`](super::TIMEOUT_PERIODS) ticks from the next one. Cartesian mode
    /// only; refused while a move or sequence runs.
    pub fn stream_twist(&mut self, twist: Twist, frame: TwistFrame) -> Result<(), Refusal> {
        if !twist.iter().all(|v| v.is_finite()) {
            return Err(Refusal::InvalidNumber);
        }
        self.ready_for_stream(Mode::Cartesian)?;
        self.stream.command(StreamCommand::Twist(twist, frame));
        Ok(())
    }

    /// Streams joint rates (rad/s, or m/s for prismatic joints), one per joint, valid for
    /// [`TIMEOUT_PERIODS`](super::TIMEOUT_PERIODS) ticks from the next one. Joint mode only;
    /// refused while a move or sequence runs.
    pub fn stream_joint_rates(&mut self, rates: &[f64]) -> Result<(), Refusal> {
        let rates = self.chain.check(rates).map_err(|e| match e {
            KinematicsError::WrongJointCount => Refusal::WrongJointCount,
            KinematicsError::NonFiniteJoints => Refusal::InvalidNumber,
        })?;
        self.ready_for_stream(Mode::Joint)?;
        self.stream.command(StreamCommand::JointRates(rates));
        Ok(())
    }

    fn ready_for_stream(&self, mode: Mode) -> Result<(), Refusal> {
        if self.mode != mode {
            return Err(Refusal::WrongMode);
        }
        if self.measured.is_none() {
            return Err(Refusal::NotReady);
        }
        if self.is_moving() && !self.stream.is_active() {
            return Err(Refusal::Busy);
        }
        Ok(())
    }

    fn hold(&mut self, q_m: Joints) {
        let q = self.command.unwrap_or(q_m);
        self.joint_generator.hold(q);
        if let Ok(pose) = self.chain.forward(&q) {
            self.cartesian_generator.hold(pose);
        }
        self.joint_sequence.halt();
        self.cartesian_sequence.halt();
    }

    /// Moves the tool to `goal` (base frame) in at least `min_duration` seconds (negative: as
    /// fast as the limits allow). Cartesian mode only.
    /// The straight line to the goal is checked first (docs/protocol.md): a move the arm cannot
    /// follow is refused with where and why.
    pub fn move_cartesian(&mut self, goal: Frame, min_duration: f64) -> Result<f64, Refusal> {
        self.ready_for_cartesian_motion(&goal, min_duration)?;
        if let Some(mut reach) = self.reach() {
            let (start, seed) = self.cartesian_start();
            reach.line(&start, &goal, &seed)?;
        }
        self.cartesian_generator
            .move_to(goal, min_duration.max(0.0))
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
        })
    }

    /// Moves the joints to `goal` in at least `min_duration` seconds. Joint mode only.
    pub fn move_joints(&mut self, goal: &[f64], min_duration: f64) -> Result<f64, Refusal> {
        let goal = self.ready_for_joint_motion(goal, min_duration)?;
        self.joint_generator.move_to(goal, min_duration.max(0.0))
    }

    /// Runs a circle or sinusoid from the current set-point. Cartesian mode only.
    pub fn start_shape(&mut self, shape: Shape) -> Result<(), Refusal> {
        self.ready_for_cartesian_motion(&self.cartesian_generator.setpoint(), 0.0)?;
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

    /// Empties the Cartesian via-point slots.
    pub fn clear_cartesian_via(&mut self) {
        self.cartesian_sequence.clear();
    }

    /// Empties the joint via-point slots.
    pub fn clear_joint_via(&mut self) {
        self.joint_sequence.clear();
    }

    /// Runs the Cartesian via points 0, 1, … up to the first empty slot. Cartesian mode only.
    /// Every leg's straight line is checked first, as for a move.
    pub fn start_cartesian_sequence(&mut self) -> Result<(), Refusal> {
        self.ready_for_cartesian_motion(&self.cartesian_generator.setpoint(), 0.0)?;
        if let Some(mut reach) = self.reach() {
            let (mut from, mut q) = self.cartesian_start();
            for via in self.cartesian_sequence.ready() {
                q = reach.line(&from, &via.point, &q)?;
                from = via.point;
            }
        }
        let first = self.cartesian_sequence.start()?;
        let then = self.cartesian_sequence.towards();
        self.cartesian_generator
            .move_towards(first.point, first.min_duration, then)
            .map(|_| ())
    }

    /// Runs the joint via points 0, 1, … up to the first empty slot. Joint mode only.
    pub fn start_joint_sequence(&mut self) -> Result<(), Refusal> {
        if self.mode != Mode::Joint {
            return Err(Refusal::WrongMode);
        }
        if self.is_moving() {
            return Err(Refusal::Busy);
        }
        let first = self.joint_sequence.start()?;
        let then = self.joint_sequence.towards();
        self.joint_generator
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

    /// The control mode.
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// True while a move, shape or sequence of the active mode runs.
    pub fn is_moving(&self) -> bool {
        match self.mode {
            Mode::Off => false,
            Mode::Joint | Mode::Cartesian if self.stream.is_active() => true,
            Mode::Joint => self.joint_generator.is_moving() || self.joint_sequence.is_running(),
            Mode::Cartesian => {
                self.cartesian_generator.is_moving() || self.cartesian_sequence.is_running()
            }
        }
    }

    /// What the arm is doing: which kind of motion runs in the active mode.
    pub fn motion(&self) -> Motion {
        match self.mode {
            Mode::Off => Motion::Holding,
            Mode::Joint | Mode::Cartesian if self.stream.is_active() => Motion::Streaming,
            Mode::Joint if self.joint_sequence.is_running() => Motion::JointSequence,
            Mode::Joint if self.joint_generator.is_moving() => Motion::JointMove,
            Mode::Cartesian if self.cartesian_sequence.is_running() => Motion::CartesianSequence,
            Mode::Cartesian if self.cartesian_generator.is_moving() => Motion::CartesianMove,
            Mode::Joint | Mode::Cartesian => Motion::Holding,
        }
    }

    /// The last joint command (none while off).
    pub fn command(&self) -> Option<Joints> {
        self.command
    }

    /// The last measured joints and their FK.
    pub fn measured(&self) -> Option<(Joints, Frame)> {
        self.measured
    }

    /// The Cartesian generator's set-point.
    pub fn cartesian_setpoint(&self) -> Frame {
        self.cartesian_generator.setpoint()
    }

    /// How long a streamed command holds (s): [`TIMEOUT_PERIODS`](super::TIMEOUT_PERIODS)
    /// control periods. `TW` and `jW` echo it in f6, so that a client knows how often to send.
    pub fn stream_timeout(&self) -> f64 {
        f64::from(super::TIMEOUT_PERIODS) * self.period
    }

    /// The velocity stream (TW, jW).
    pub fn stream(&self) -> &VelocityStream {
        &self.stream
    }

    /// The IK settings of the robot file.
    pub fn ik_config(&self) -> &IkConfig {
        &self.ik
    }

    /// The kinematic chain.
    pub fn chain(&self) -> &Chain {
        &self.chain
    }
}

fn note_sequence<P>(step: SequenceStep<P>, events: &mut Events) {
    match step {
        SequenceStep::Finished => events.sequence_finished = true,
        SequenceStep::Aborted => events.sequence_aborted = true,
        SequenceStep::Wait | SequenceStep::MoveTo(_) => {}
    }
}

/// How far `q` lies inside the joint limits: its distance to the nearest one (0 if outside).
fn limit_margin(chain: &Chain, q: &Joints) -> f64 {
    q.iter()
        .zip(chain.min().iter().zip(chain.max()))
        .map(|(v, (lo, hi))| (v - lo).min(hi - v))
        .fold(f64::INFINITY, f64::min)
        .max(0.0)
}

/// Euclidean distance between joint vectors (the joint sequence's reach metric).
fn joint_distance(a: &Joints, b: &Joints) -> f64 {
    libm::sqrt(a.iter().zip(b.iter()).map(|(x, y)| (x - y) * (x - y)).sum())
}
