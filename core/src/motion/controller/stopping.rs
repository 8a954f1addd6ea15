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
        let scale = self.within_cartesian_limits(t0, &before, braked, from);
        if scale > braked {
            brake.ease_to(scale, from);
        }
        let t_next = t0 + scale * self.period;
        let sample = self.cartesian_generator.sample(t_next);
        let (setpoint, finished) = sample;
        let Tracking::Reached(q) = self.track(&setpoint, q_cmd) else {
            return None;
        };
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

    /// The scale nearest the brake's `scale` (`from`: the last one) at which the step from
    /// `before` (motion time `t0`) changes no Cartesian axis's velocity by more than its
    /// acceleration limit over a period. The brake's budget bounds the change the scale makes
    /// at the path's present full speed; it can miss two ways. The path may slow down by itself
    /// while the stop brakes (a line's own deceleration phase): the two together reached
    /// 1.97 × a per-axis limit before (issue 33); the scale then falls less, at most back to
    /// `from`. A stop that begins while the motion runs below full speed (its time scale below
    /// 1, near a singularity) would speed it up at its first scale; the scale then falls
    /// further, down to 0 at most. Along a path the step's velocity grows with the scale: a
    /// bisection finds the edge.
    fn within_cartesian_limits(&self, t0: f64, before: &Frame, scale: f64, from: f64) -> f64 {
        let Some(too_fast) = self.cartesian_excess(t0, before, scale) else {
            return scale;
        };
        let (mut lo, mut hi) = if too_fast {
            (0.0, scale)
        } else {
            (scale, from.max(scale))
        };
        for _ in 0..BISECTIONS {
            let mid = 0.5 * (lo + hi);
            // Too fast: the scale must fall further; within: as near the brake's as may be.
            let excess = self.cartesian_excess(t0, before, mid);
            let lower = if too_fast {
                excess == Some(true)
            } else {
                excess != Some(false)
            };
            if lower {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        if too_fast { lo } else { hi }
    }

    /// Whether the step from `before` to the set-point at motion time `t0 + s` periods changes
    /// some Cartesian axis's velocity by more than its acceleration limit over a period:
    /// `Some(true)` speeding up (the step faster than the last), `Some(false)` slowing down,
    /// `None` within every limit.
    fn cartesian_excess(&self, t0: f64, before: &Frame, s: f64) -> Option<bool> {
        let t = self.period;
        let (ahead, _) = self.cartesian_generator.sample(t0 + s * t);
        let v = cartesian_velocity(before, &ahead, t);
        let last = &self.cartesian_step;
        let limits = v
            .iter()
            .zip(last.iter())
            .zip(self.cartesian_acceleration.iter());
        let beyond = limits
            .into_iter()
            .any(|((v, w), a)| libm::fabs(v - w) > a * t * (1.0 + 1e-9));
        let square = |x: &[f64; 6]| x.iter().map(|c| c * c).sum::<f64>();
        beyond.then(|| square(&v) > square(last))
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
