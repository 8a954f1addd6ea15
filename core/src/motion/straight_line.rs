//! A synchronised straight-line move in n dimensions with per-axis limits.
//!
//! The seed (OCL) gave every axis its own trapezoid and stretched them to a common duration,
//! so axes with different profile shapes drifted off the straight segment (spec §4.2, §9
//! item 23). Here one trapezoid drives the path parameter along the segment, with the speed and
//! acceleration along the path limited so that no axis exceeds its own limit: the path is
//! exactly straight and all axes start and finish together. For a move along a single axis
//! this is the seed's profile exactly.

use super::trapezoid::Trapezoid;
use crate::MAX_JOINTS;

/// A straight move from `start` to `start + direction · length` (up to [`MAX_JOINTS`] axes).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StraightLine {
    start: [f64; MAX_JOINTS],
    /// Unit direction (zero for a zero-length move).
    direction: [f64; MAX_JOINTS],
    n: usize,
    profile: Trapezoid,
}

impl StraightLine {
    /// Plans the minimum-time move from `start` to `goal` (both `n` long) whose per-axis speed
    /// and acceleration stay within `v_max` and `a_max`.
    pub fn plan(start: &[f64], goal: &[f64], v_max: &[f64], a_max: &[f64]) -> Self {
        let mut line = Self {
            n: start.len().min(goal.len()).min(MAX_JOINTS),
            ..Self::default()
        };
        let mut length2 = 0.0;
        for ((s, d), (a, b)) in line
            .start
            .iter_mut()
            .zip(line.direction.iter_mut())
            .zip(start.iter().zip(goal))
        {
            *s = *a;
            *d = b - a;
            length2 += *d * *d;
        }
        let length = libm::sqrt(length2);
        if length.is_nan() || length <= 0.0 {
            line.direction = [0.0; MAX_JOINTS];
            return line;
        }
        // Path limits: axis k moves at |u_k| times the path speed.
        let (mut v_path, mut a_path) = (f64::INFINITY, f64::INFINITY);
        for ((d, v), a) in line.direction.iter_mut().zip(v_max).zip(a_max).take(line.n) {
            *d /= length;
            let u = libm::fabs(*d);
            if u > 0.0 {
                v_path = v_path.min(v / u);
                a_path = a_path.min(a / u);
            }
        }
        line.profile = Trapezoid::plan(0.0, length, v_path, a_path);
        line
    }

    /// Stretches the move to `duration` if that is longer than its minimum time.
    pub fn stretched(self, duration: f64) -> Self {
        Self {
            profile: self.profile.stretched(duration),
            ..self
        }
    }

    /// Minimum (or stretched) duration (s).
    pub fn duration(&self) -> f64 {
        self.profile.duration()
    }

    /// Length of the segment.
    pub fn length(&self) -> f64 {
        self.profile.position(f64::INFINITY)
    }

    /// The point at time `t`, written to `out[..n]`.
    pub fn point(&self, t: f64, out: &mut [f64]) {
        let s = self.profile.position(t);
        for ((o, a), d) in out
            .iter_mut()
            .zip(&self.start)
            .zip(&self.direction)
            .take(self.n)
        {
            *o = a + d * s;
        }
    }

    /// The path speed at time `t`.
    pub fn speed(&self, t: f64) -> f64 {
        self.profile.velocity(t)
    }

    /// Distance travelled along the segment by time `t`.
    pub fn progress(&self, t: f64) -> f64 {
        self.profile.position(t)
    }

    /// The unit direction, one entry per axis (zeros for a zero-length move).
    pub fn direction(&self) -> &[f64] {
        self.direction.get(..self.n).unwrap_or(&[])
    }

    /// True if the limits allow no motion along a segment of nonzero length (a zero limit on
    /// an axis it moves along): the profile would jump to the goal.
    pub fn is_stuck(&self) -> bool {
        let moves = self.profile.duration() > 0.0;
        self.length() > 0.0 && !moves
    }

    /// The largest path acceleration of the (stretched) profile.
    pub fn peak_acceleration(&self) -> f64 {
        self.profile.peak_acceleration()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn diagonal_move_respects_the_binding_axis() {
        // x must move 0.3, y 0.4: |u| = (0.6, 0.8); y binds the speed at 0.1/0.8.
        let line = StraightLine::plan(&[0.0, 0.0], &[0.3, 0.4], &[0.1, 0.1], &[1.0, 1.0]);
        assert!((line.length() - 0.5).abs() < 1e-15);
        let peak = line.speed(line.duration() / 2.0);
        assert!((peak * 0.8 - 0.1).abs() < 1e-12);
        let mut p = [0.0; 2];
        line.point(line.duration() * 0.3, &mut p);
        assert!(
            (p[0] * 0.8 - p[1] * 0.6).abs() < 1e-15,
            "off the line: {p:?}"
        );
    }

    #[test]
    fn single_axis_move_is_the_plain_trapezoid() {
        let line = StraightLine::plan(&[1.0, 2.0], &[1.0, 2.5], &[0.2, 0.1], &[0.3, 0.1]);
        let plain = Trapezoid::plan(0.0, 0.5, 0.1, 0.1);
        assert_eq!(line.duration(), plain.duration());
    }

    #[test]
    fn zero_move_stays_put() {
        let line =
            StraightLine::plan(&[1.0, 2.0], &[1.0, 2.0], &[1.0; 2], &[1.0; 2]).stretched(3.0);
        let mut p = [0.0; 2];
        line.point(1.0, &mut p);
        assert_eq!(p, [1.0, 2.0]);
        assert_eq!(line.duration(), 0.0);
    }
}
