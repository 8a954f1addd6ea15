//! A stop in progress, one tick at a time: along a Cartesian or joint path (the brake scales
//! the generator's motion time), or in joint space (`joint_stop.rs`).

use super::cartesian_tick::{Tracking, cartesian_velocity};
use super::{Controller, Mode};
use crate::kinematics::Joints;
use crate::math::Frame;
use crate::motion::Events;
use crate::motion::brake::budget;
use crate::motion::supervisor::Along;

impl Controller {
    /// One tick of the stop in progress (begun earlier or this tick): its command, and the
    /// Cartesian set-point of a stop along a Cartesian path. At rest the generators hold where
    /// it ended and the stop is over.
    pub(super) fn stopping_tick(
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
        let from = brake.scale();
        let braked = brake.next(rate, change);
        let eased = self.within_cartesian_limits(t0, &before, braked, from);
        // The joints first: where they cannot follow the eased step (near a singularity the
        // joints' speed along the path is not the tool's), the brake's own.
        // A step the joints reach only beyond an acceleration limit is taken too, as the tick
        // takes one: the limiter eases it and the tool leaves the path by a little, rather
        // than the stop leaving it for joint space (issue 33).
        let mut tracked = None;
        for scale in [eased, braked] {
            let t_next = t0 + scale * self.period;
            let sample = self.cartesian_generator.sample(t_next);
            if let Tracking::Reached(q) | Tracking::Abrupt(q) = self.track(&sample.0, q_cmd) {
                tracked = Some((scale, t_next, sample, q));
                break;
            }
            if eased <= braked {
                break;
            }
        }
        let (scale, t_next, sample, q) = tracked?;
        let (setpoint, finished) = sample;
        if scale > braked {
            brake.ease_to(scale, from);
        }
        if let Some(stop) = self.supervisor.stopping_mut() {
            stop.brake = brake;
        }
        self.cartesian_step = cartesian_velocity(&before, &setpoint, self.period);
        self.cartesian_generator.commit(t_next, sample);
        if finished || scale <= 0.0 {
            self.supervisor.finish();
            self.joint_generator.hold(q);
            self.cartesian_generator.hold(setpoint);
            self.cartesian_sequence.halt();
        }
        Some((Some(q), Some(setpoint)))
    }

    /// The smallest scale in `scale..=from` (`from`: the last one) at which the step from
    /// `before` (motion time `t0`) changes no Cartesian axis's velocity by more than its
    /// acceleration limit over a period. The brake's budget bounds the change the scale makes
    /// at the path's present speed; the path may slow down by itself at the same time (a
    /// line's own deceleration phase, reached while the stop still brakes), and the two
    /// together reached 1.97 × a per-axis limit before (issue 33). Where the path slows down,
    /// the scale falls less; along a path the step's velocity grows with the scale, so a
    /// bisection finds it.
    fn within_cartesian_limits(&self, t0: f64, before: &Frame, scale: f64, from: f64) -> f64 {
        let t = self.period;
        let within = |s: f64| {
            let (ahead, _) = self.cartesian_generator.sample(t0 + s * t);
            let v = cartesian_velocity(before, &ahead, t);
            let change = v.iter().zip(self.cartesian_step.iter());
            change
                .zip(self.cartesian_acceleration.iter())
                .all(|((v, w), a)| libm::fabs(v - w) <= a * t * (1.0 + 1e-9))
        };
        if from <= scale || within(scale) {
            return scale;
        }
        let (mut lo, mut hi) = (scale, from);
        for _ in 0..BISECTIONS {
            let mid = 0.5 * (lo + hi);
            if within(mid) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        hi
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
}

/// Halvings of the interval in which a stop along a Cartesian path looks for its scale: 2⁻³⁰
/// of the scale, far below what a set-point can show.
const BISECTIONS: u32 = 30;

/// Joint velocity of the step from `a` to `b` over `dt`.
fn joint_velocity(a: &Joints, b: &Joints, dt: f64) -> Joints {
    let mut v = *b;
    for (v, a) in v.iter_mut().zip(a.iter()) {
        *v = (*v - a) / dt;
    }
    v
}
