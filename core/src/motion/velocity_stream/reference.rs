//! The path a twist stream means: a reference pose that advances with the commanded twist as
//! far as the arm actually follows it, and a correction back to it.
//!
//! The stream is open loop otherwise: an orientation given up at a singularity (or a drift of
//! the first-order steps) would stay. The reference starts where the tool is when a command
//! (a twist in a frame) starts, and advances each tick by that twist times the share of it the
//! arm achieved (projected, weighted as the damping is), so that a slow-down, a stop at a joint
//! margin or at the workspace never winds it up; what the arm lost sideways is won back at
//! [`GAIN`], at most [`CORRECTION_SHARE`] of each Cartesian limit. A different command starts
//! a new reference where the tool is, and a zero twist has none: stopping never pulls the arm
//! back over the distance it needed to brake. (After a change of direction the arm rounds the
//! corner within its acceleration limits and then returns to the new line.)

use armgate_protocol::client::TwistFrame;

use super::LINEAR_WEIGHT;
use crate::math::{self, Frame, Rotation3, Twist, Vector3};
use crate::saturate::saturate;

/// Rate at which a deviation from the reference is corrected (1/s).
pub const GAIN: f64 = 2.0;

/// The correction is at most this share of each axis's Cartesian speed limit.
pub const CORRECTION_SHARE: f64 = 0.25;

/// The reference pose of a twist stream (none while no twist is streamed).
#[derive(Clone, Copy, Debug, Default)]
pub struct PathReference {
    pose: Option<Frame>,
    /// The command the reference belongs to.
    command: Option<(Twist, TwistFrame)>,
}

impl PathReference {
    /// The twist (base frame) that brings the tool at `at` back to the reference of
    /// `command`, within `CORRECTION_SHARE × limits`; a new command's reference starts at `at`.
    pub fn correction(
        &mut self,
        at: &Frame,
        command: (Twist, TwistFrame),
        limits: &[f64; 6],
    ) -> Twist {
        if command.0.iter().all(|v| *v == 0.0) {
            // Holding still: nothing to follow, and the braking is not to be undone.
            self.clear();
            return Twist::zeros();
        }
        if self.command != Some(command) {
            self.command = Some(command);
            self.pose = None;
        }
        let reference = *self.pose.get_or_insert(*at);
        let mut twist = math::diff(at, &reference) * GAIN;
        for (v, max) in twist.iter_mut().zip(limits) {
            let cap = CORRECTION_SHARE * max;
            *v = saturate(*v, -cap, cap);
        }
        if twist.iter().all(|v| v.is_finite()) {
            twist
        } else {
            Twist::zeros()
        }
    }

    /// Advances the reference by `intended · period` times the share of it the step from
    /// `from` to `to` achieved (0..=1).
    pub fn advance(&mut self, intended: &Twist, from: &Frame, to: &Frame, period: f64) {
        let Some(pose) = self.pose.as_mut() else {
            return;
        };
        let achieved = math::diff(from, to);
        let weight = |i: usize| {
            if i < 3 {
                LINEAR_WEIGHT * LINEAR_WEIGHT
            } else {
                1.0
            }
        };
        let (along, norm) = intended
            .iter()
            .zip(achieved.iter())
            .enumerate()
            .fold((0.0, 0.0), |(a, n), (i, (x, d))| {
                (a + weight(i) * x * d, n + weight(i) * x * x * period)
            });
        // NaN (a zero intended twist) or no progress: the reference stays.
        let share = saturate(along / norm, 0.0, 1.0);
        if share.is_nan() || share == 0.0 {
            return;
        }
        let step = intended * (share * period);
        pose.translation.vector += step.fixed_rows::<3>(0);
        let turn: Vector3<f64> = step.fixed_rows::<3>(3).into_owned();
        pose.rotation = Rotation3::new(turn) * pose.rotation;
    }

    /// Forgets the reference (no twist streamed).
    pub fn clear(&mut self) {
        self.pose = None;
        self.command = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_reference_advances_by_what_the_arm_achieved_and_corrects_sideways() {
        let limits = [0.1, 0.1, 0.1, 0.5, 0.5, 0.5];
        let mut reference = PathReference::default();
        let start = Frame::identity();
        // Commanded 0.1 m/s along x for 0.1 s; the arm made half of it, and 1 mm along y.
        let intended = Twist::new(0.1, 0.0, 0.0, 0.0, 0.0, 0.0);
        let command = (intended, TwistFrame::Base);
        let correction = |r: &mut PathReference, at| r.correction(at, command, &limits);
        assert_eq!(correction(&mut reference, &start), Twist::zeros());
        let to = Frame::translation(0.005, 0.001, 0.0);
        reference.advance(&intended, &start, &to, 0.1);
        let c = correction(&mut reference, &to);
        // The reference is at x = 5 mm: nothing to correct along x, −1 mm along y.
        assert!(c[0].abs() < 1e-12 && (c[1] + 0.002).abs() < 1e-12, "{c:?}");
        // A large deviation is corrected at most at a quarter of the limit.
        let far = Frame::translation(0.005, 0.5, 0.0);
        assert_eq!(correction(&mut reference, &far)[1], -0.025);
        // An arm that did not move does not advance the reference.
        reference.advance(&intended, &to, &to, 0.1);
        assert!(correction(&mut reference, &to)[0].abs() < 1e-12);
        // Another command, or none, starts afresh where the tool is.
        let stop = (Twist::zeros(), TwistFrame::Base);
        assert_eq!(reference.correction(&far, stop, &limits), Twist::zeros());
        reference.clear();
        assert_eq!(correction(&mut reference, &far), Twist::zeros());
    }
}
