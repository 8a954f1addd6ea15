//! The control step: one deterministic tick of the whole motion pipeline (spec §1.4), and the
//! requests that start, stop and switch motions.
//!
//! The tick's parts, one concern a file: `controller/cartesian_tick.rs` (Cartesian mode: time
//! scale, look-ahead, tracking IK), `controller/joint_tick.rs` (joint mode),
//! `controller/streaming.rs` (the velocity stream's requests and tick) and
//! `controller/stopping.rs` (a stop in progress). The motion requests likewise:
//! `controller/cartesian_requests.rs` and `controller/joint_requests.rs`.

mod cartesian_requests;
mod cartesian_tick;
mod following;
mod joint_requests;
mod joint_tick;
mod stopping;
mod streaming;

use super::body::Body;
use super::brake::{Brake, budget};
use super::cartesian_generator::CartesianGenerator;
use super::fixed_point::FixedPoint;
use super::joint_generator::JointGenerator;
use super::joint_limiter::JointLimiter;
use super::sequence::{Sequence, SequenceStep, Tolerances};
use super::supervisor::{Along, StopCause, Supervisor};
use super::velocity_stream::VelocityStream;
use super::workspace::Workspace;
use super::{Events, Refusal};
use crate::config::{IkConfig, ValidRobot};
use crate::kinematics::{Chain, Joints, KinematicsError, LastEvaluation};
use crate::math::Frame;
use armgate_protocol::client::Motion;

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

/// The control mode: a rule of the wire (`CM`), defined once in the protocol crate.
pub use armgate_protocol::client::Mode;
pub use cartesian_requests::CartesianPlan;

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
    /// The arm's body: capsules kept out of the boxes, in the bounds, clear of each other.
    body: Body,
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
    /// Every transition to rest, and the commanded velocity.
    supervisor: Supervisor,
    /// The Cartesian motion's time scale (1: as planned), kept from tick to tick: a slow-down
    /// near a singularity or a joint limit changes it within the joints' acceleration limits.
    time_scale: f64,
    /// The Cartesian set-point's velocity at full time scale, from the last tick's step.
    cartesian_nominal: [f64; 6],
    /// The Cartesian set-point's velocity over the last tick's step, as commanded: what a stop
    /// along the path keeps each axis's change of within its acceleration limit.
    cartesian_step: [f64; 6],
    /// Cartesian limits (x, y, z, rx, ry, rz): acceleration, and jerk if set.
    cartesian_acceleration: [f64; 6],
    cartesian_jerk: Option<[f64; 6]>,
    /// Cartesian speed limits, and the joints' rate and acceleration limits (for the line
    /// check).
    cartesian_speed: [f64; 6],
    max_rate: Joints,
    max_acceleration: Joints,
    /// The last tracking solve that returned its seed: a holding arm's solve, not repeated.
    fixed_point: FixedPoint,
    /// The tracking solves' last pose evaluation: the next tick's seed, evaluated already.
    last_evaluation: LastEvaluation,
    /// Each joint's `max_following_error` (`following.rs`).
    following_limit: Joints,
    /// A following error stopped the arm and some joint is still beyond its limit.
    lagging: bool,
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
            body: Body::new(config),
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
            supervisor: Supervisor::new(config),
            time_scale: 1.0,
            cartesian_nominal: [0.0; 6],
            cartesian_step: [0.0; 6],
            cartesian_acceleration: cartesian.max_acceleration,
            cartesian_jerk: cartesian_j_max,
            cartesian_speed: cartesian.max_velocity,
            max_rate: config.per_joint(|j| j.max_rate),
            max_acceleration: a_max,
            fixed_point: FixedPoint::default(),
            last_evaluation: LastEvaluation::default(),
            following_limit: config.following_limits(),
            lagging: false,
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
        self.check_following(&q_m, &mut events);
        let mut stream_finished = false;
        let running = match self.mode {
            _ if self.supervisor.is_stopping() => None,
            Mode::Off => Some((None, None)),
            Mode::Joint | Mode::Cartesian if self.stream.expires() => {
                // A silent client: the supervisor brings the arm to rest.
                self.stream.halt();
                let along = self.supervisor.in_joint_space();
                self.supervisor.begin(StopCause::StreamTimeout, along);
                None
            }
            Mode::Joint | Mode::Cartesian if self.stream.is_active() => {
                let step = self.stream_tick(&q_m, &mut events);
                stream_finished = step.finished;
                let setpoint = (self.mode == Mode::Cartesian).then_some(step.pose);
                Some((Some(step.q), setpoint))
            }
            Mode::Joint => Some((Some(self.joint_tick(&q_m, &mut events)), None)),
            Mode::Cartesian => self
                .cartesian_tick(&q_m, &f_m, &mut events)
                .map(|(q, sp)| (Some(q), Some(sp))),
        };
        // A stop in progress, or one that began this tick: the supervisor commands.
        let (request, setpoint) = match running {
            Some(out) => out,
            None => self.stopping_tick(&q_m, &mut events),
        };
        let previous = self.command.unwrap_or(q_m);
        let command = request.map(|r| {
            let limited = self
                .limiter
                .limit(&r, &previous, self.supervisor.velocity());
            events.joint_limit = limited.position_clamped;
            events.rate_limit = limited.rate_clamped || limited.acceleration_clamped;
            limited.q
        });
        match &command {
            Some(q) => {
                self.supervisor.observe(q, &previous);
                self.command = command;
            }
            None => {
                // Nothing commanded (mode off): the next command starts from rest.
                self.supervisor.reset();
                self.command = None;
            }
        }
        // The body where it is commanded and where a stop begun now would end: a new hit stops.
        // A Cartesian motion's stop brakes along its path within the Cartesian limits too.
        let path_rate = if self.mode == Mode::Cartesian && !self.stream.is_active() {
            budget(
                &self.cartesian_step,
                &self.cartesian_acceleration,
                self.period,
            )
        } else {
            f64::INFINITY
        };
        // A joint move's stop ends on its straight way, short of its goal (not so for a
        // stream's or a mode change's stop in joint space).
        let in_joint_space = self
            .supervisor
            .stopping()
            .is_some_and(|s| s.along != Along::Path);
        let end = (self.mode == Mode::Joint
            && !self.stream.is_active()
            && !stream_finished
            && !in_joint_space)
            .then(|| self.joint_generator.straight_end())
            .flatten();
        if let Some(q) = &command
            && let Some(hit) = self.body.check_tick(
                &self.chain,
                q,
                (self.supervisor.velocity(), path_rate),
                end.as_ref(),
                self.stream.is_active(),
            )
            && !self.supervisor.is_stopping()
        {
            events.collision = Some(hit);
            self.stop(StopCause::Workspace);
            // In joint space, whatever the motion: the check looked ahead along the joints'
            // velocity, where that stop ends. Along a Cartesian path near a singularity the
            // joints slow down less than the path and went on further: hybrid's unchecked line
            // in stop_bench ended 4.5 mm into its own link 4 (issue 35's oracle).
            self.supervisor.leave_path();
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

    /// Switches the control mode. The newly active generator holds the last command (or the
    /// measured joints when coming from off), so the switch itself never moves the arm.
    /// Selecting the current mode again stops any motion. While the arm moves, the supervisor
    /// first brings it to rest in joint space (cause [`StopCause::ModeChange`]); the new mode
    /// holds where it stops (mode off: no command from then on).
    pub fn set_mode(&mut self, mode: Mode) -> Result<(), Refusal> {
        let (q_m, _) = self.measured.ok_or(Refusal::NotReady)?;
        let moving = self.is_moving() && self.command.is_some();
        self.mode = mode;
        self.stream.halt();
        self.hold(q_m);
        if moving {
            let along = self.supervisor.in_joint_space();
            self.supervisor.finish();
            self.supervisor.begin(StopCause::ModeChange, along);
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
        self.supervisor.reset();
        if let Some((q_m, _)) = self.measured {
            self.hold(q_m);
        }
    }

    /// Stops every motion and sequence, for `cause` (`ST`, `OF`, a client's watchdog, …): the
    /// one way to rest. A moving arm decelerates within every joint's acceleration (and jerk)
    /// limits — a move or sequence along its path, a stream in joint space — and then holds;
    /// [`is_moving`](Self::is_moving) stays true until it is at rest. A held arm just stays.
    /// A stop whose cause latches ([`latches`](super::latches)), in motion or at rest, leaves
    /// streams refused until the holder starts a motion on purpose.
    pub fn stop(&mut self, cause: StopCause) {
        if !self.is_moving() || self.command.is_none() {
            if let Some((q_m, _)) = self.measured {
                self.hold(q_m);
            }
            self.supervisor.at_rest(cause);
            return;
        }
        if self.stream.is_active() {
            self.stream.halt();
            let along = self.supervisor.in_joint_space();
            self.supervisor.begin(cause, along);
            if let Some(q) = self.command {
                self.hold_at(q);
            }
            return;
        }
        self.joint_sequence.halt();
        self.cartesian_sequence.halt();
        self.begin_path_stop(cause);
    }

    /// Starts a stop along the running motion's path. A Cartesian one brakes from the speed
    /// the path runs at, its time scale (below 1 where the tick slowed it down, near a
    /// singularity): from full scale its first tick would speed the path up, beyond the joints'
    /// acceleration, and the stop would leave the path for joint space (iiwa14's line in
    /// stop_bench, before).
    fn begin_path_stop(&mut self, cause: StopCause) {
        let fresh = !self.supervisor.is_stopping();
        self.supervisor.begin(cause, Along::Path);
        if fresh
            && self.mode == Mode::Cartesian
            && let Some(stop) = self.supervisor.stopping_mut()
        {
            stop.brake = Brake::at(self.time_scale);
        }
    }

    /// The stop or hold cause in force (`SQ` index 2), and the joint of a joint-limit hold.
    pub fn stop_cause(&self) -> (Option<StopCause>, Option<u8>) {
        (self.supervisor.cause(), self.supervisor.held_joint())
    }

    fn hold(&mut self, q_m: Joints) {
        self.hold_at(self.command.unwrap_or(q_m));
    }

    /// Every generator holds `q` (the Cartesian one its tool pose); sequences end.
    fn hold_at(&mut self, q: Joints) {
        self.joint_generator.hold(q);
        if let Ok(pose) = self.chain.forward(&q) {
            self.cartesian_generator.hold(pose);
        }
        self.joint_sequence.halt();
        self.cartesian_sequence.halt();
    }

    /// The control mode.
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// True while a move, shape or sequence of the active mode runs.
    pub fn is_moving(&self) -> bool {
        if self.supervisor.is_stopping() {
            return true;
        }
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
            _ if self.supervisor.is_stopping() => Motion::Stopping,
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

    /// The arm's body and its checks.
    pub fn body(&self) -> &Body {
        &self.body
    }
}

fn note_sequence<P>(step: SequenceStep<P>, events: &mut Events) {
    match step {
        SequenceStep::Finished => events.sequence_finished = true,
        SequenceStep::Aborted => events.sequence_aborted = true,
        SequenceStep::Wait | SequenceStep::MoveTo(_) => {}
    }
}
