//! The joint limiter (spec §5.1): the last guard before a set-point reaches the drives.

use crate::config::ValidRobot;
use crate::kinematics::Joints;
use crate::saturate::{limit_step, saturate};

/// Clamps each joint set-point to its range, its step to `max_rate · period`, and the change
/// of its step to `max_acceleration · period²` (its acceleration, against the previous
/// commanded velocity): the last clamp before the drives, so nothing after it can introduce a
/// velocity step.
#[derive(Clone, Debug)]
pub struct JointLimiter {
    min: Joints,
    max: Joints,
    max_step: Joints,
    /// The largest change of a step from one tick to the next.
    max_change: Joints,
    period: f64,
}

/// A limited set-point and what was clamped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limited {
    /// The set-point to command.
    pub q: Joints,
    /// A joint was requested outside its range (the seed's `JointLimitEvent`).
    pub position_clamped: bool,
    /// A joint's step exceeded its rate limit.
    pub rate_clamped: bool,
    /// A joint's step changed by more than its acceleration limit allows.
    pub acceleration_clamped: bool,
}

impl JointLimiter {
    /// The limiter of a robot.
    pub fn new(config: &ValidRobot) -> Self {
        Self {
            min: config.per_joint(|j| j.min),
            max: config.per_joint(|j| j.max),
            max_step: config.per_joint(|j| j.max_rate * config.control_period),
            max_change: config
                .per_joint(|j| j.max_acceleration * config.control_period * config.control_period),
            period: config.control_period,
        }
    }

    /// How far moving from `previous` to `q` in one tick exceeds the rate limits: the largest
    /// ratio of a joint's step to its allowed step (≤ 1 means within every limit). A step that
    /// is not a number (NaN or infinite values) gives infinity, never a ratio that passes.
    pub fn rate_ratio(&self, q: &Joints, previous: &Joints) -> f64 {
        q.iter()
            .zip(previous.iter())
            .zip(self.max_step.iter())
            .map(|((a, b), step)| {
                let ratio = libm::fabs(a - b) / step;
                if ratio.is_nan() { f64::INFINITY } else { ratio }
            })
            .fold(0.0, f64::max)
    }

    /// How far moving from `previous` to `q` exceeds the acceleration limits after a step at
    /// `velocity`: the largest ratio of a joint's change of step to its allowed change (NaN:
    /// infinity).
    pub fn acceleration_ratio(&self, q: &Joints, previous: &Joints, velocity: &Joints) -> f64 {
        q.iter()
            .zip(previous.iter().zip(velocity.iter()))
            .zip(self.max_change.iter())
            .map(|((a, (b, v)), change)| {
                let ratio = libm::fabs(a - b - v * self.period) / change;
                if ratio.is_nan() { f64::INFINITY } else { ratio }
            })
            .fold(0.0, f64::max)
    }

    /// Limits `request` given the previous command and the commanded joint velocity that led
    /// to it (of the same arm, so of the same length; zero from rest). A request exactly at a
    /// limit is not a violation (the seed raised its event there on every tick, spec §9 item
    /// 26); the seed ignored the rate in position mode (§9 item 27), here it is enforced, and
    /// so is the acceleration. The range wins over the acceleration: a set-point is never
    /// commanded outside it (the generators and streams plan to stop within it, so this only
    /// matters for requests that do not).
    ///
    /// The output is finite whenever `previous` is (the controller's previous command, or the
    /// measured joints, which are checked): a NaN or infinite request holds the joint at its
    /// previous value and counts as a position clamp, so it never reaches the drives' unit
    /// conversion. Every test is written so that NaN fails it.
    pub fn limit(&self, request: &Joints, previous: &Joints, velocity: &Joints) -> Limited {
        let mut out = Limited {
            q: *request,
            position_clamped: false,
            rate_clamped: false,
            acceleration_clamped: false,
        };
        let bounds = self
            .min
            .iter()
            .zip(self.max.iter())
            .zip(self.max_step.iter().zip(self.max_change.iter()));
        let steps = previous.iter().zip(velocity.iter());
        for ((v, (prev, vel)), ((lo, hi), (step, change))) in
            out.q.iter_mut().zip(steps).zip(bounds)
        {
            if !v.is_finite() {
                out.position_clamped = true;
                *v = *prev;
            }
            let within_range = *lo <= *v && *v <= *hi;
            if !within_range {
                out.position_clamped = true;
                *v = saturate(*v, *lo, *hi);
            }
            let limited = saturate(*v, prev - step, prev + step);
            let within_rate = limited == *v;
            if !within_rate {
                out.rate_clamped = true;
                *v = limited;
            }
            // The window of steps within the acceleration limit; it overlaps the rate window,
            // since the last step was within it.
            let last = vel * self.period;
            let (low, high) = (last - change, last + change);
            // Rounding in a plan within the limit (1e-9 of it) is left as it is.
            let wanted = *v - prev;
            let excess = (low - wanted).max(wanted - high);
            if excess > 1e-9 * change && low.is_finite() && high.is_finite() {
                out.acceleration_clamped = true;
                let wanted = saturate(wanted, low, high);
                *v = saturate(prev + limit_step(wanted, *step), *lo, *hi);
            }
        }
        out
    }
}
