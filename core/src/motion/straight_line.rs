//! A synchronised straight-line move in n dimensions with per-axis limits.
//!
//! The seed (OCL) gave every axis its own trapezoid and stretched them to a common duration,
//! so axes with different profile shapes drifted off the straight segment (spec §4.2, §9
//! item 23). Here one profile drives the path parameter along the segment, with the speed and
//! acceleration (and, jerk-limited, the jerk) along the path limited so that no axis exceeds
//! its own limit: the path is exactly straight and all axes start and finish together. For a
//! trapezoidal move along a single axis this is the seed's profile exactly.

use super::profile::{DoubleS, JerkLimits, ProfileError};
use super::trapezoid::Trapezoid;
use crate::MAX_JOINTS;

/// A straight move from `start` to `start + direction · length` (up to [`MAX_JOINTS`] axes).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StraightLine {
    start: [f64; MAX_JOINTS],
    /// Unit direction (zero for a zero-length move).
    direction: [f64; MAX_JOINTS],
    n: usize,
    profile: PathProfile,
}

/// The profile of the path parameter: the seed's trapezoid, or jerk-limited.
#[derive(Clone, Copy, Debug, PartialEq)]
enum PathProfile {
    Trapezoid(Trapezoid),
    JerkLimited(DoubleS),
}

impl Default for PathProfile {
    fn default() -> Self {
        Self::Trapezoid(Trapezoid::default())
    }
}

impl StraightLine {
    /// Plans the minimum-time trapezoidal move from `start` to `goal` (both `n` long) whose
    /// per-axis speed and acceleration stay within `v_max` and `a_max`.
    pub fn plan(start: &[f64], goal: &[f64], v_max: &[f64], a_max: &[f64]) -> Self {
        let mut line = Self::segment(start, goal);
        let length = line.length_of_direction();
        if length > 0.0 {
            let limits = line.path_limits(v_max, a_max, &[f64::INFINITY; MAX_JOINTS]);
            line.profile = PathProfile::Trapezoid(Trapezoid::plan(
                0.0,
                length,
                limits.velocity,
                limits.acceleration,
            ));
        }
        line
    }

    /// Plans the minimum-time jerk-limited (double-S) move from `start` to `goal` whose
    /// per-axis speed, acceleration and jerk stay within `v_max`, `a_max` and `j_max`.
    /// Errors only for limits that are not finite and positive, or a move whose times overflow.
    pub fn plan_jerk_limited(
        start: &[f64],
        goal: &[f64],
        v_max: &[f64],
        a_max: &[f64],
        j_max: &[f64],
    ) -> Result<Self, ProfileError> {
        let mut line = Self::segment(start, goal);
        let length = line.length_of_direction();
        let limits = if length > 0.0 {
            line.path_limits(v_max, a_max, j_max)
        } else {
            // A zero-length move needs no limits: any valid ones give a rest.
            JerkLimits::new(1.0, 1.0, 1.0)
        };
        line.profile = PathProfile::JerkLimited(DoubleS::new(length, limits, 0.0)?);
        Ok(line)
    }

    /// [`plan_jerk_limited`](Self::plan_jerk_limited) with jerk limits `j_max`, else
    /// [`plan`](Self::plan): the generators' one entry, whichever profile the robot file chose.
    pub fn plan_with(
        start: &[f64],
        goal: &[f64],
        v_max: &[f64],
        a_max: &[f64],
        j_max: Option<&[f64]>,
    ) -> Result<Self, ProfileError> {
        match j_max {
            Some(j_max) => Self::plan_jerk_limited(start, goal, v_max, a_max, j_max),
            None => Ok(Self::plan(start, goal, v_max, a_max)),
        }
    }

    /// The segment from `start` to `goal` with its unnormalised direction and no profile.
    fn segment(start: &[f64], goal: &[f64]) -> Self {
        let mut line = Self {
            n: start.len().min(goal.len()).min(MAX_JOINTS),
            ..Self::default()
        };
        for ((s, d), (a, b)) in line
            .start
            .iter_mut()
            .zip(line.direction.iter_mut())
            .zip(start.iter().zip(goal))
        {
            *s = *a;
            *d = b - a;
        }
        line
    }

    /// Normalises the direction and returns the length; a zero or non-finite length leaves a
    /// zero direction and gives 0.
    fn length_of_direction(&mut self) -> f64 {
        let length = crate::math::sqrt(self.direction.iter().map(|d| d * d).sum::<f64>());
        if length.is_nan() || length <= 0.0 || length.is_infinite() {
            self.direction = [0.0; MAX_JOINTS];
            return 0.0;
        }
        for d in &mut self.direction {
            *d /= length;
        }
        length
    }

    /// Path limits: axis k moves at `|u_k|` times the path's rate, so the path's limits are the
    /// smallest of each axis' limits divided by `|u_k|` (axes that do not move bind nothing).
    fn path_limits(&self, v_max: &[f64], a_max: &[f64], j_max: &[f64]) -> JerkLimits {
        let unbounded = JerkLimits::new(f64::INFINITY, f64::INFINITY, f64::INFINITY);
        self.direction
            .iter()
            .zip(v_max.iter().zip(a_max).zip(j_max))
            .take(self.n)
            .filter(|(u, _)| **u != 0.0)
            .fold(unbounded, |path, (u, ((v, a), j))| {
                path.min(JerkLimits::new(*v, *a, *j).along(*u))
            })
    }

    /// Stretches the move to `duration` if that is longer than its minimum time. (A
    /// jerk-limited move whose stretched times would overflow an `f64` keeps its own.)
    pub fn stretched(self, duration: f64) -> Self {
        let profile = match self.profile {
            PathProfile::Trapezoid(p) => PathProfile::Trapezoid(p.stretched(duration)),
            PathProfile::JerkLimited(p) => {
                PathProfile::JerkLimited(p.with_duration(duration).unwrap_or(p))
            }
        };
        Self { profile, ..self }
    }

    /// Minimum (or stretched) duration (s).
    pub fn duration(&self) -> f64 {
        match &self.profile {
            PathProfile::Trapezoid(p) => p.duration(),
            PathProfile::JerkLimited(p) => p.duration(),
        }
    }

    /// Length of the segment.
    pub fn length(&self) -> f64 {
        self.path(f64::INFINITY).0
    }

    /// The path parameter and its rate at time `t`.
    fn path(&self, t: f64) -> (f64, f64) {
        match &self.profile {
            PathProfile::Trapezoid(p) => (p.position(t), p.velocity(t)),
            PathProfile::JerkLimited(p) => {
                let (s, v, _) = p.sample(t);
                (s, v)
            }
        }
    }

    /// The point at time `t`, written to `out[..n]`.
    pub fn point(&self, t: f64, out: &mut [f64]) {
        let s = self.path(t).0;
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
        self.path(t).1
    }

    /// Distance travelled along the segment by time `t`.
    pub fn progress(&self, t: f64) -> f64 {
        self.path(t).0
    }

    /// The unit direction, one entry per axis (zeros for a zero-length move).
    pub fn direction(&self) -> &[f64] {
        self.direction.get(..self.n).unwrap_or(&[])
    }

    /// True if the limits allow no motion along a segment of nonzero length (a zero limit on
    /// an axis it moves along): the profile would jump to the goal.
    pub fn is_stuck(&self) -> bool {
        let moves = self.duration() > 0.0;
        self.length() > 0.0 && !moves
    }

    /// The largest path acceleration of the (stretched) profile.
    pub fn peak_acceleration(&self) -> f64 {
        match &self.profile {
            PathProfile::Trapezoid(p) => p.peak_acceleration(),
            PathProfile::JerkLimited(p) => p.peak_acceleration(),
        }
    }

    /// A bound on the path jerk: the jerk-limited profile's limit; 0 for a trapezoid, which
    /// has no jerk limit (its acceleration jumps).
    pub fn peak_jerk(&self) -> f64 {
        match &self.profile {
            PathProfile::Trapezoid(_) => 0.0,
            PathProfile::JerkLimited(p) => p.limits().jerk,
        }
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
    fn jerk_limited_diagonal_respects_each_axis_and_stays_on_the_line() {
        // |u| = (0.6, 0.8): the path may jerk at min(1/0.6, 0.5/0.8) = 0.625, x binds velocity.
        let line = StraightLine::plan_jerk_limited(
            &[0.0, 0.0],
            &[0.3, 0.4],
            &[0.06, 1.0],
            &[1.0, 1.0],
            &[1.0, 0.5],
        )
        .unwrap();
        let PathProfile::JerkLimited(profile) = line.profile else {
            panic!("not jerk-limited");
        };
        assert_eq!(profile.limits(), JerkLimits::new(0.1, 1.25, 0.625));
        assert!((line.length() - 0.5).abs() < 1e-15);
        let mut p = [0.0; 2];
        line.point(line.duration() * 0.3, &mut p);
        assert!(
            (p[0] * 0.8 - p[1] * 0.6).abs() < 1e-15,
            "off the line: {p:?}"
        );
        line.point(line.duration(), &mut p);
        assert_eq!(p, [0.3, 0.4]);
        // Stretching keeps the end and lasts exactly as asked.
        let slow = line.stretched(10.0);
        assert!((slow.duration() - 10.0).abs() < 1e-12);
        assert!(slow.speed(5.0) < line.speed(line.duration() / 2.0));
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
