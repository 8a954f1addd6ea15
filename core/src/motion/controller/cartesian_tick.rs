//! The Cartesian mode's tick: via-point sequence, generator, the time scale with memory, the
//! look-ahead to the workspace's edge and the boxes, and the tracking IK.

use super::{Controller, REACH_TOLERANCE, note_sequence};
use crate::kinematics::Joints;
use crate::math::{self, Frame};
use crate::motion::Events;
use crate::motion::brake::budget;
use crate::motion::sequence::SequenceStep;
use crate::motion::supervisor::StopCause;

/// How a Cartesian set-point can be tracked this tick.
pub(super) enum Tracking {
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

impl Controller {
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
    pub(super) fn cartesian_tick(
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
                -0.5 * delta + crate::math::sqrt(0.25 * delta * delta + 2.0 * delta * n)
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
                    self.cartesian_step = cartesian_velocity(&before, &setpoint, self.period);
                    self.cartesian_generator.commit(t, sample);
                    events.motion_finished |= finished && !self.cartesian_sequence.is_running();
                    let unchecked = !self.ik.check_lines || self.cartesian_generator.runs_shape();
                    if moving && !finished && unchecked && self.boundary_ahead(&setpoint, t) {
                        events.workspace_limit = true;
                        self.begin_path_stop(StopCause::Workspace);
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
            self.cartesian_step = cartesian_velocity(&before, &sample.0, self.period);
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

    /// Tracking IK from `seed` to `setpoint`, checked against the reach tolerance and the
    /// joints' rate limits. A solve known to return its seed is not repeated ([`FixedPoint`]).
    pub(super) fn track(&mut self, setpoint: &Frame, seed: &Joints) -> Tracking {
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
}

/// Cartesian velocity (x, y, z, rx, ry, rz) of the step from `a` to `b` over `dt`.
pub(super) fn cartesian_velocity(a: &Frame, b: &Frame, dt: f64) -> [f64; 6] {
    let d: [f64; 6] = math::diff(a, b).into();
    d.map(|x| if dt > 0.0 { x / dt } else { 0.0 })
}
