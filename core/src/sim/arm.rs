//! Simulated arms: what the drives would report for a stream of joint commands.

use crate::kinematics::Joints;
use crate::saturate::limit_step;

/// An arm that reaches every command instantly (the seed's `SimArm` in position mode).
#[derive(Clone, Debug)]
pub struct IdealArm {
    q: Joints,
}

impl IdealArm {
    /// An arm resting at `q`.
    pub fn new(q: Joints) -> Self {
        Self { q }
    }

    /// Applies this tick's command (`None`: hold).
    pub fn step(&mut self, command: Option<&Joints>) {
        if let Some(c) = command.filter(|c| c.len() == self.q.len() && c.is_finite()) {
            self.q = *c;
        }
    }

    /// The measured joints.
    pub fn measured(&self) -> Joints {
        self.q
    }
}

/// An arm whose joints follow the command with bounded velocity and acceleration.
///
/// Unlike the seed's `SimArm_nAxes`, which restarted a trapezoid from rest on every new
/// command and so crawled behind a stream of set-points (spec §9 item 40), each joint keeps its
/// velocity and steers towards the latest command, braking in time to stop on it.
#[derive(Clone, Debug)]
pub struct RateLimitedArm {
    q: Joints,
    velocity: Joints,
    target: Joints,
    v_max: Joints,
    a_max: Joints,
}

impl RateLimitedArm {
    /// An arm resting at `q` with per-joint limits.
    pub fn new(q: Joints, v_max: Joints, a_max: Joints) -> Self {
        Self {
            q,
            velocity: Joints::zeros(q.len()),
            target: q,
            v_max,
            a_max,
        }
    }

    /// Applies this tick's command (`None`: keep the last one) and advances by `dt` seconds.
    pub fn step(&mut self, command: Option<&Joints>, dt: f64) {
        if let Some(c) = command.filter(|c| c.len() == self.q.len() && c.is_finite()) {
            self.target = *c;
        }
        if !(dt > 0.0 && dt.is_finite()) {
            return; // no time passes
        }
        let limits = self.v_max.iter().zip(self.a_max.iter());
        let state = self
            .q
            .iter_mut()
            .zip(self.velocity.iter_mut())
            .zip(self.target.iter());
        for (((q, v), target), (v_max, a_max)) in state.zip(limits) {
            let error = target - *q;
            let dv = a_max * dt;
            // The fastest speed v that, after moving v·dt this step, still lets the joint stop on
            // the target in whole steps of deceleration a: v² + 3·dv·v ≤ 2·a·|error|.
            let brake = 0.5
                * (crate::math::sqrt(9.0 * dv * dv + 8.0 * a_max * libm::fabs(error)) - 3.0 * dv);
            let wanted = libm::copysign(brake.min(*v_max), error);
            *v += limit_step(wanted - *v, dv);
            *q += *v * dt;
        }
    }

    /// The measured joints.
    pub fn measured(&self) -> Joints {
        self.q
    }
}
