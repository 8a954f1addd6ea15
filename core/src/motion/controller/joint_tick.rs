//! The joint mode's tick: via-point sequence (blends within the joint limits), then the
//! generator.

use super::{Controller, note_sequence};
use crate::kinematics::{Chain, Joints};
use crate::motion::Events;
use crate::motion::sequence::SequenceStep;

impl Controller {
    /// Joint mode: sequence, then generator.
    pub(super) fn joint_tick(&mut self, q_m: &Joints, events: &mut Events) -> Joints {
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
    crate::math::sqrt(a.iter().zip(b.iter()).map(|(x, y)| (x - y) * (x - y)).sum())
}
