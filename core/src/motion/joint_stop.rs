//! A stop in joint space: the arm's present acceleration ramped out first (where the robot
//! file limits jerk), then the velocity it has reached scaled down to zero by a [`Brake`],
//! every joint by the same fraction, so the direction of motion is kept while it comes to rest.
//!
//! The brake starts from no deceleration; an arm that was accelerating (a blend, a stream
//! ramping up) would see its acceleration step to zero in one tick. Ramping it out first keeps
//! every joint within `max_jerk` from whatever state the motion was in.

use super::brake::{Brake, budget};
use crate::config::ValidRobot;
use crate::kinematics::Joints;
use crate::saturate::saturate;

/// The limits a joint-space stop keeps.
#[derive(Clone, Debug)]
pub struct StopLimits {
    /// Per joint: acceleration, and jerk if the robot file limits it.
    pub a_max: Joints,
    pub j_max: Option<Joints>,
    /// Control period (s).
    pub period: f64,
}

impl StopLimits {
    /// A robot's limits.
    pub fn new(config: &ValidRobot) -> Self {
        Self {
            a_max: config.per_joint(|j| j.max_acceleration),
            j_max: config.joint_jerk_limits(),
            period: config.control_period,
        }
    }

    /// The brake's budgets for a joint velocity `nominal` at scale 1: the largest fall of the
    /// scale per tick within every joint's acceleration limit, and the largest change of that
    /// fall within the jerk limits (infinite without them).
    pub fn budget(&self, nominal: &Joints) -> (f64, f64) {
        let t = self.period;
        let rate = budget(nominal, &self.a_max, t);
        let change = self
            .j_max
            .map_or(f64::INFINITY, |j| budget(nominal, &j, t * t));
        (rate, change)
    }
}

/// A joint-space stop in progress.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointStop {
    /// The velocity the brake scales: the commanded one once the acceleration is out.
    from: Joints,
    brake: Brake,
    /// Still ramping out the acceleration the arm had.
    settling: bool,
}

impl JointStop {
    /// The stop of an arm last commanded at `velocity` with `acceleration`.
    pub fn new(velocity: &Joints, acceleration: &Joints, limits: &StopLimits) -> Self {
        Self {
            from: *velocity,
            brake: Brake::default(),
            settling: limits.j_max.is_some() && acceleration.iter().any(|a| *a != 0.0),
        }
    }

    /// The next tick's velocity after the last commanded `velocity` and `acceleration`, and the
    /// brake's scale (0: at rest). While settling, every joint's acceleration falls towards
    /// zero by at most its jerk limit × period; the tick it is zero on every joint, the brake
    /// takes the velocity reached (from the next tick).
    pub fn next(
        &mut self,
        velocity: &Joints,
        acceleration: &Joints,
        limits: &StopLimits,
    ) -> (Joints, f64) {
        if let (true, Some(j_max)) = (self.settling, &limits.j_max) {
            let t = limits.period;
            let mut v = *velocity;
            let mut left = false;
            for ((v, a), j) in v.iter_mut().zip(acceleration.iter()).zip(j_max.iter()) {
                let next = a - saturate(*a, -j * t, j * t);
                left |= next != 0.0;
                *v += next * t;
            }
            if !left {
                *self = Self {
                    from: v,
                    brake: Brake::default(),
                    settling: false,
                };
            }
            return (v, 1.0);
        }
        let (rate, change) = limits.budget(&self.from);
        let scale = self.brake.next(rate, change);
        let mut v = self.from;
        v.iter_mut().for_each(|v| *v *= scale);
        (v, scale)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn joints(v: &[f64]) -> Joints {
        Joints::from_slice(v).unwrap()
    }

    /// Runs a stop from `v`, `a` as the controller does (the command it gives is the one it
    /// sees next tick); returns the largest acceleration and jerk per joint over the limits.
    fn run(v: &[f64], a: &[f64], limits: &StopLimits) -> (f64, f64, usize) {
        let t = limits.period;
        let (mut v, mut a) = (joints(v), joints(a));
        let mut stop = JointStop::new(&v, &a, limits);
        let (mut peak_a, mut peak_j) = (0.0f64, 0.0f64);
        for tick in 1..10_000 {
            let (next, scale) = stop.next(&v, &a, limits);
            for i in 0..v.len() {
                let acc = (next[i] - v[i]) / t;
                peak_a = peak_a.max(acc.abs() / limits.a_max[i]);
                if let Some(j) = &limits.j_max {
                    peak_j = peak_j.max((acc - a[i]).abs() / t / j[i]);
                }
                a[i] = acc;
            }
            v = next;
            if scale <= 0.0 {
                assert!(v.iter().all(|x| *x == 0.0));
                return (peak_a, peak_j, tick);
            }
        }
        panic!("no rest");
    }

    fn limits(jerk: bool) -> StopLimits {
        StopLimits {
            a_max: joints(&[0.5, 0.5, 0.05]),
            j_max: jerk.then(|| joints(&[5.0, 5.0, 0.1])),
            period: 0.01944,
        }
    }

    #[test]
    fn an_accelerating_arm_stops_within_the_jerk_limits() {
        let (a, j, _) = run(&[0.3, -0.2, 0.01], &[0.5, 0.4, -0.05], &limits(true));
        assert!(a <= 1.0 + 1e-9, "acceleration {a}");
        assert!(j <= 1.0 + 1e-9, "jerk {j}");
    }

    #[test]
    fn at_cruise_the_brake_starts_at_once() {
        let cruise = run(&[0.3, -0.2, 0.01], &[0.0; 3], &limits(true));
        let accelerating = run(&[0.3, -0.2, 0.01], &[0.5, 0.4, -0.05], &limits(true));
        assert!(cruise.1 <= 1.0 + 1e-9);
        assert!(cruise.2 < accelerating.2);
    }

    #[test]
    fn without_jerk_limits_nothing_settles() {
        let limits = limits(false);
        let (v, a) = (joints(&[0.3, -0.2, 0.01]), joints(&[0.5, 0.4, -0.05]));
        let mut stop = JointStop::new(&v, &a, &limits);
        let (next, scale) = stop.next(&v, &a, &limits);
        assert!(scale < 1.0);
        assert!((next[0] / v[0] - scale).abs() < 1e-12);
    }
}
