//! The control step: one deterministic tick of the whole motion pipeline (spec §1.4).

use super::cartesian_generator::CartesianGenerator;
use super::fixed_point::FixedPoint;
use super::joint_generator::JointGenerator;
use super::joint_limiter::JointLimiter;
use super::joint_path::check_joint_path;
use super::reach::{Reach, check_iterations, joint_beyond_limit};
use super::sequence::{Sequence, SequenceStep, Tolerances, ViaPoint};
use super::shape::Shape;
use super::brake::budget;
use super::supervisor::{Along, StopCause, Supervisor};
use super::velocity_stream::{StreamCommand, StreamStep, VelocityStream};
use super::workspace::Workspace;
use super::{Events, Refusal};
use crate::config::{IkConfig, ValidRobot};
use crate::kinematics::{Chain, Joints, KinematicsError, LastEvaluation};
use crate::math::{self, Frame, Twist};
use armgate_protocol::client::{Hold, JointBound, Motion, PathPoint, TwistFrame};

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

/// How a Cartesian set-point can be tracked this tick.
enum Tracking {
    /// Reached within the tolerance and the rate limits.
    Reached(Joints),
    /// Reached within the rate limits, but some joint would exceed its acceleration limit
    /// (the limiter then eases the step, and the tool leaves the path a little).
    Abrupt(Joints),
    /// Reached, but some joint would exceed its rate limit.
    TooFast,
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
    /// Every transition to rest, and the commanded velocity.
    supervisor: Supervisor,
    /// The Cartesian motion's time scale (1: as planned), kept from tick to tick: a slow-down
    /// near a singularity or a joint limit changes it within the joints' acceleration limits.
    time_scale: f64,
    /// The Cartesian set-point's velocity at full time scale, from the last tick's step.
    cartesian_nominal: [f64; 6],
    /// Cartesian limits (x, y, z, rx, ry, rz): acceleration, and jerk if set.
    cartesian_acceleration: [f64; 6],
    cartesian_jerk: Option<[f64; 6]>,
    /// Cartesian speed limits, and the joints' rate limits (for the line check).
    cartesian_speed: [f64; 6],
    max_rate: Joints,
    /// The last tracking solve that returned its seed: a holding arm's solve, not repeated.
    fixed_point: FixedPoint,
    /// The tracking solves' last pose evaluation: the next tick's seed, evaluated already.
    last_evaluation: LastEvaluation,
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
            supervisor: Supervisor::new(config),
            time_scale: 1.0,
            cartesian_nominal: [0.0; 6],
            cartesian_acceleration: cartesian.max_acceleration,
            cartesian_jerk: cartesian_j_max,
            cartesian_speed: cartesian.max_velocity,
            max_rate: config.per_joint(|j| j.max_rate),
            fixed_point: FixedPoint::default(),
            last_evaluation: LastEvaluation::default(),
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
            None if step.workspace_limit => Some(Hold::Workspace),
            None => None,
        };
        self.supervisor.hold(events.hold);
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
    /// singularity) raises [`Events::ik_divergence`] and the supervisor brings the arm to rest
    /// in joint space. So does a measured pose outside the workspace (`ER21`); a set-point
    /// that would come within the stopping distance of the workspace's edge or a box starts a
    /// stop along the path, which ends before it. `None`: a stop began, the supervisor
    /// commands this tick.
    fn cartesian_tick(
        &mut self,
        q_m: &Joints,
        f_m: &Frame,
        events: &mut Events,
    ) -> Option<(Joints, Frame)> {
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
        let moving = self.cartesian_generator.is_moving();
        let t0 = self.cartesian_generator.elapsed();
        let before = self.cartesian_generator.setpoint();
        // The time scale may change by as much as the joints' and the Cartesian acceleration
        // limits allow at the speeds of full scale: up first, then the same, then down. A
        // motion that starts at speed (a shape) starts from scale 0.
        let (s, cartesian_nominal) = match (moving, t0 > 0.0) {
            (false, _) => (1.0, [0.0; 6]),
            (true, true) => (self.time_scale, self.cartesian_nominal),
            (true, false) => {
                let (ahead, _) = self.cartesian_generator.sample(self.period);
                (0.0, cartesian_velocity(&before, &ahead, self.period))
            }
        };
        let mut nominal = *self.supervisor.velocity();
        if s > 0.0 {
            nominal.iter_mut().for_each(|v| *v /= s);
        }
        let (joint_delta, _) = self.supervisor.joint_budget(&nominal);
        let c_a = &self.cartesian_acceleration;
        let delta = joint_delta.min(budget(&cartesian_nominal, c_a, self.period));
        // A shape that ends at speed: slow down so that the scale is down to about one step's
        // change when the end comes (the scale s covers s²/2δ + s/2 periods while it falls).
        let cap = self
            .cartesian_generator
            .time_to_abrupt_end()
            .map_or(1.0, |left| {
                let n = left / self.period;
                -0.5 * delta + libm::sqrt(0.25 * delta * delta + 2.0 * delta * n)
            });
        // The slowest step that only the acceleration clamp keeps from being reached.
        let mut abrupt = None;
        let down = (s - delta).max(0.0);
        let up = (s + delta).min(1.0).min(cap).max(down);
        for scale in [up, s.min(cap).max(down), down] {
            if scale <= 0.0 {
                break;
            }
            let t = t0 + self.period * scale;
            let sample = self.cartesian_generator.sample(t);
            let (setpoint, finished) = sample;
            if events.workspace_limit || !self.workspace.allows(&setpoint.translation.vector) {
                // An illegal set-point never reaches the IK: the arm comes to rest in joint
                // space and the motion is aborted.
                events.workspace_limit = true;
                self.abort_cartesian_motion(StopCause::Workspace, events);
                return None;
            }
            let tracked = match self.track(&setpoint, &seed) {
                Tracking::Abrupt(q) => {
                    abrupt = Some((q, scale, t, sample));
                    continue;
                }
                other => other,
            };
            match tracked {
                Tracking::Abrupt(_) | Tracking::TooFast => {}
                Tracking::Reached(q) => {
                    self.time_scale = scale;
                    self.cartesian_nominal =
                        cartesian_velocity(&before, &setpoint, self.period * scale);
                    self.cartesian_generator.commit(t, sample);
                    events.motion_finished |= finished && !self.cartesian_sequence.is_running();
                    let unchecked = !self.ik.check_lines || self.cartesian_generator.runs_shape();
                    if moving && !finished && unchecked && self.boundary_ahead(&setpoint, t) {
                        events.workspace_limit = true;
                        self.supervisor.begin(StopCause::Workspace, Along::Path);
                        self.cartesian_sequence.halt();
                    }
                    return Some((q, setpoint));
                }
                Tracking::Unreachable => break,
            }
        }
        if let Some((q, scale, t, sample)) = abrupt {
            self.time_scale = scale;
            self.cartesian_nominal = cartesian_velocity(&before, &sample.0, self.period * scale);
            self.cartesian_generator.commit(t, sample);
            events.motion_finished |= sample.1 && !self.cartesian_sequence.is_running();
            return Some((q, sample.0));
        }
        events.ik_divergence = true;
        let _ = f_m;
        self.abort_cartesian_motion(StopCause::IkDivergence, events);
        None
    }

    /// True if the Cartesian motion, at `setpoint` (motion time `t`), would leave the
    /// workspace or enter an exclusion box within its stopping distance along the path: the
    /// point where a stop along the path beginning next tick would end (half the stopping time
    /// at the present full-scale speed, plus the jerk ramp and two ticks, of motion time) and
    /// the straight way there. Only for what was not checked before it started (shapes, and
    /// lines when the robot file turns the check off).
    fn boundary_ahead(&self, setpoint: &Frame, t: f64) -> bool {
        let stop_time = self
            .cartesian_nominal
            .iter()
            .zip(self.cartesian_acceleration.iter())
            .map(|(v, a)| libm::fabs(*v) / a)
            .fold(0.0, f64::max);
        let ramp = self.cartesian_jerk.map_or(0.0, |j| {
            self.cartesian_acceleration
                .iter()
                .zip(j.iter())
                .map(|(a, j)| a / j)
                .fold(0.0, f64::max)
        });
        let horizon = 0.5 * stop_time + ramp + 2.0 * self.period;
        let (ahead, _) = self.cartesian_generator.sample(t + horizon);
        let (here, there) = (&setpoint.translation.vector, &ahead.translation.vector);
        !self.workspace.allows(there) || self.workspace.first_box_crossing(here, there).is_some()
    }

    /// One tick of the stop in progress (begun earlier or this tick): its command, and the
    /// Cartesian set-point of a stop along a Cartesian path. At rest the generators hold where
    /// it ended and the stop is over.
    fn stopping_tick(
        &mut self,
        q_m: &Joints,
        events: &mut Events,
    ) -> (Option<Joints>, Option<Frame>) {
        let Some(stop) = self.supervisor.stopping().copied() else {
            return (None, None);
        };
        let q_cmd = self.command.unwrap_or(*q_m);
        if stop.along == Along::Path && self.mode == Mode::Cartesian {
            if let Some(out) = self.cartesian_path_stop(&q_cmd) {
                return out;
            }
            // The path cannot be followed: on in joint space.
            events.ik_divergence = true;
            self.supervisor.leave_path();
        } else if stop.along == Along::Path && self.mode == Mode::Joint {
            let mut peek = self.joint_generator.clone();
            let before = self.joint_generator.setpoint();
            let (ahead, _) = peek.advance(self.period);
            let nominal = joint_velocity(&before, &ahead, self.period);
            let (rate, change) = self.supervisor.joint_budget(&nominal);
            let scale = self.brake(rate, change);
            let (q, finished) = self.joint_generator.advance(scale * self.period);
            if finished || scale <= 0.0 {
                self.finish_stop(&q);
            }
            return (Some(q), None);
        }
        let Some((mut v, scale)) = self.supervisor.next_joint_velocity() else {
            self.finish_stop(&q_cmd);
            return (Some(q_cmd), None);
        };
        self.supervisor.keep_within_range(&q_cmd, &mut v);
        let mut q = q_cmd;
        for (q, v) in q.iter_mut().zip(v.iter()) {
            *q += v * self.period;
        }
        if scale <= 0.0 {
            self.finish_stop(&q);
        }
        (Some(q), None)
    }

    /// A stop along a Cartesian path: the motion time advances by the brake's scale of a
    /// period, within the Cartesian limits at the path's nominal speed and the joints' at the
    /// speed they were commanded. `None` if the IK cannot follow the path.
    fn cartesian_path_stop(&mut self, q_cmd: &Joints) -> Option<(Option<Joints>, Option<Frame>)> {
        let t0 = self.cartesian_generator.elapsed();
        let before = self.cartesian_generator.setpoint();
        let (ahead, _) = self.cartesian_generator.sample(t0 + self.period);
        let nominal = cartesian_velocity(&before, &ahead, self.period);
        let t = self.period;
        let mut rate = budget(&nominal, &self.cartesian_acceleration, t);
        let mut change = self
            .cartesian_jerk
            .map_or(f64::INFINITY, |j| budget(&nominal, &j, t * t));
        // The joints at the speed the scale stands for now.
        let scale_now = self.supervisor.stopping().map_or(1.0, |s| s.brake.scale());
        if scale_now > 0.0 {
            let mut joints = *self.supervisor.velocity();
            joints.iter_mut().for_each(|v| *v /= scale_now);
            let (r, c) = self.supervisor.joint_budget(&joints);
            (rate, change) = (rate.min(r), change.min(c));
        }
        let mut brake = self.supervisor.stopping()?.brake;
        let scale = brake.next(rate, change);
        let t_next = t0 + scale * self.period;
        let sample = self.cartesian_generator.sample(t_next);
        let (setpoint, finished) = sample;
        let Tracking::Reached(q) = self.track(&setpoint, q_cmd) else {
            return None;
        };
        if let Some(stop) = self.supervisor.stopping_mut() {
            stop.brake = brake;
        }
        self.cartesian_generator.commit(t_next, sample);
        if finished || scale <= 0.0 {
            self.supervisor.finish();
            self.joint_generator.hold(q);
            self.cartesian_generator.hold(setpoint);
            self.cartesian_sequence.halt();
        }
        Some((Some(q), Some(setpoint)))
    }

    /// The next scale of the stop in progress (0 if none).
    fn brake(&mut self, rate: f64, change: f64) -> f64 {
        self.supervisor
            .stopping_mut()
            .map_or(0.0, |stop| stop.brake.next(rate, change))
    }

    /// The stop has come to rest at `q`: the generators hold there.
    fn finish_stop(&mut self, q: &Joints) {
        self.supervisor.finish();
        self.hold_at(*q);
    }

    /// Tracking IK from `seed` to `setpoint`, checked against the reach tolerance and the
    /// joints' rate limits. A solve known to return its seed is not repeated ([`FixedPoint`]).
    fn track(&mut self, setpoint: &Frame, seed: &Joints) -> Tracking {
        if self.fixed_point.holds(setpoint, seed) {
            return Tracking::Reached(*seed);
        }
        let solved =
            self.chain
                .solve_tracking_after(setpoint, seed, &self.ik, &mut self.last_evaluation);
        let Ok(result) = solved else {
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
        if self.limiter.rate_ratio(&s.q, seed) > 1.0 {
            return Tracking::TooFast;
        }
        if !self.supervisor.can_stop_within_range(seed, &s.q) {
            return Tracking::Unreachable;
        }
        let velocity = self.supervisor.velocity();
        if self.limiter.acceleration_ratio(&s.q, seed, velocity) > 1.0 + 1e-9 {
            return Tracking::Abrupt(s.q);
        }
        self.fixed_point.note(setpoint, seed, &s.q);
        Tracking::Reached(s.q)
    }

    /// Aborts the Cartesian motion (and its sequence): the supervisor brings the arm to rest
    /// in joint space from the commanded velocity, and the generators then hold there.
    fn abort_cartesian_motion(&mut self, cause: StopCause, events: &mut Events) {
        events.sequence_aborted |= self.cartesian_sequence.is_running();
        self.cartesian_sequence.halt();
        let setpoint = self.cartesian_generator.setpoint();
        self.cartesian_generator.hold(setpoint);
        let along = self.supervisor.in_joint_space();
        self.supervisor.begin(cause, along);
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
    pub fn stop(&mut self, cause: StopCause) {
        if !self.is_moving() || self.command.is_none() {
            if let Some((q_m, _)) = self.measured {
                self.hold(q_m);
            }
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
        self.supervisor.begin(cause, Along::Path);
    }

    /// The stop or hold cause in force (`SQ` index 2), and the joint of a joint-limit hold.
    pub fn stop_cause(&self) -> (Option<StopCause>, Option<u8>) {
        (self.supervisor.cause(), self.supervisor.held_joint())
    }

    /// Streams a tool twist `[vx, vy, vz, ωx, ωy, ωz]` (m/s, rad/s) in `frame`, valid for
    /// [`TIMEOUT_PERIODS`](super::TIMEOUT_PERIODS) ticks from the next one. Cartesian mode
    /// only; refused while a move or sequence runs.
    pub fn stream_twist(&mut self, twist: Twist, frame: TwistFrame) -> Result<(), Refusal> {
        if !twist.iter().all(|v| v.is_finite()) {
            return Err(Refusal::InvalidNumber);
        }
        self.ready_for_stream(Mode::Cartesian)?;
        self.supervisor.clear_cause();
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
        self.supervisor.clear_cause();
        self.stream.command(StreamCommand::JointRates(rates));
        Ok(())
    }

    /// A stream may start, or resume while its own stop (`ST`, its timeout) is under way: it
    /// then takes over from the velocity commanded last, within the same limits.
    fn ready_for_stream(&mut self, mode: Mode) -> Result<(), Refusal> {
        if self.mode != mode {
            return Err(Refusal::WrongMode);
        }
        if self.measured.is_none() {
            return Err(Refusal::NotReady);
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

    /// Moves the tool to `goal` (base frame) in at least `min_duration` seconds (negative: as
    /// fast as the limits allow). Cartesian mode only.
    /// The straight line to the goal is checked first (docs/protocol.md): a move the arm cannot
    /// follow is refused with where and why.
    pub fn move_cartesian(&mut self, goal: Frame, min_duration: f64) -> Result<f64, Refusal> {
        self.ready_for_cartesian_motion(&goal, min_duration)?;
        let min_duration = min_duration.max(0.0);
        if let Some(mut reach) = self.reach() {
            let (start, seed) = self.cartesian_start();
            reach.line(&start, &goal, &seed, min_duration)?;
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
            max_rate: &self.max_rate,
        })
    }

    /// Moves the joints to `goal` in at least `min_duration` seconds. Joint mode only. The
    /// tool's way is checked first: a move into an exclusion box or out of the workspace is
    /// refused with where (driving out of a box the tool is in stays possible).
    pub fn move_joints(&mut self, goal: &[f64], min_duration: f64) -> Result<f64, Refusal> {
        let goal = self.ready_for_joint_motion(goal, min_duration)?;
        let start = self.joint_generator.setpoint();
        check_joint_path(&self.chain, &self.workspace, &start, &goal)?;
        self.supervisor.clear_cause();
        self.joint_generator.move_to(goal, min_duration.max(0.0))
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
                q = reach.line(&from, &via.point, &q, via.min_duration)?;
                from = via.point;
            }
        }
        let first = self.cartesian_sequence.start()?;
        self.supervisor.clear_cause();
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
        let mut from = self.joint_generator.setpoint();
        for via in self.joint_sequence.ready() {
            check_joint_path(&self.chain, &self.workspace, &from, &via.point)?;
            from = via.point;
        }
        let first = self.joint_sequence.start()?;
        self.supervisor.clear_cause();
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

/// Joint velocity of the step from `a` to `b` over `dt`.
fn joint_velocity(a: &Joints, b: &Joints, dt: f64) -> Joints {
    let mut v = *b;
    for (v, a) in v.iter_mut().zip(a.iter()) {
        *v = (*v - a) / dt;
    }
    v
}

/// Cartesian velocity (x, y, z, rx, ry, rz) of the step from `a` to `b` over `dt`.
fn cartesian_velocity(a: &Frame, b: &Frame, dt: f64) -> [f64; 6] {
    let d: [f64; 6] = math::diff(a, b).into();
    d.map(|x| if dt > 0.0 { x / dt } else { 0.0 })
}
