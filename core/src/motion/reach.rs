//! Checking a Cartesian move before it starts: can the arm follow the straight line from the
//! commanded pose to the goal without leaving the workspace, crossing a joint limit or losing
//! its IK solution? A move that cannot is refused up front with the reason and where along the
//! line it fails, instead of being accepted and then aborted halfway with `WN22`.
//!
//! The line is the generator's geometric path (position along the segment, orientation about
//! the fixed axis of the relative rotation, both at the same fraction of the way). Exclusion
//! boxes are checked exactly (segment against box). Reachability is checked at
//! [`LINE_SAMPLES`] points by tracking IK from one point to the next, seeded with the
//! commanded joints, as the ticks will; where a step fails the step is halved (down to 1/8),
//! so that only a real limit refuses the move. A step in which a joint moves more than
//! [`MAX_JOINT_STEP`] is halved too, down to 1/1024 of the line: from afar the nearest
//! solution may lie on another branch, where the tick, following the line past a
//! near-singularity, swings a joint through up to half a turn (and maybe into a limit). The
//! check follows that swing as the tick would; a joint that still moves that much in the
//! shortest step jumps, and refuses the line.
//!
//! The check runs inside the ticks on the firmware, a few points a tick ([`LineCheck`], in
//! slices: the request is answered when it ends), and its whole work is bounded: at most
//! [`SOLVES_PER_LINE`] tracking solves of at most 10 iterations per line, and per request (a VE
//! checks all its legs within it) an IK iteration budget proportional to the control period
//! ([`check_iterations`]). A check that runs out gives the move the benefit of the doubt. What
//! a check and a slice cost on the Cortex-M7 (`qemu-bench/run.sh`, rows "Cartesian line check"
//! and "line check slice") is in docs/kinematics.md.
//!
//! The check also measures how long each step needs at the joints' rate limits, and the line
//! is planned to last long enough for its peak speed to need at most [`RATE_SHARE`] of any
//! joint's rate at every checked step ([`planned_duration`]): the tick's time scale slows a
//! line only as fast as the acceleration limits let it, and lost lines whose joint rates grew
//! faster than that (issue 33: ranger-mk1 back to its home pose, `WN22` 23 mm short). So long,
//! too, that no checked step needs more than that share of a joint's acceleration ([`Shape`]):
//! puma560's lines, planned at Cartesian accelerations its joints cannot take, stalled in the
//! tick for minutes or ended in `WN22`. Where the joints' rates fall sharply after the first
//! step, a step of 1/1024 of the line probes its start, where the tick starts from rest: from
//! an exact singularity a sixteenth of the way hid a joint the tick cannot move fast enough
//! (hybrid's home).
//!
//! What remains unchecked (between samples, joint rates near singularities) is still caught
//! by the tick: the motion slows down or stops with `WN22`.

mod line;

use armgate_protocol::client::{JointBound, PathPoint};

use super::Refusal;
use super::body::Body;
use super::workspace::Workspace;
use crate::MAX_JOINTS;
use crate::config::IkConfig;
use crate::kinematics::{Chain, Joints, SeedAngles};
use crate::math::Frame;
pub use line::{LineCheck, POINT_WORK};

/// Points checked along a line, evenly spaced by fraction of the way; the last is the goal.
pub const LINE_SAMPLES: usize = 16;
/// Tracking solves per line at most (each failed step is retried at half the step).
pub const SOLVES_PER_LINE: usize = 4 * LINE_SAMPLES;
/// IK iterations per checked request at most (reached at periods from 15.4 ms up).
pub const CHECK_ITERATIONS: u32 = 384;
/// IK iterations per second of control period (each up to about 7,000 Cortex-M7
/// instructions with its share of FK and bookkeeping: at most about 60 % of the period at
/// 480 MHz).
const ITERATIONS_PER_SECOND: f64 = 40_000.0;
/// The fewest iterations a check gets, whatever the period (a short line needs about 48).
const MIN_CHECK_ITERATIONS: u32 = 64;

/// The IK iteration budget of one checked request for a control period (s): proportional,
/// within 64..=[`CHECK_ITERATIONS`] (201 at 5.04 ms).
pub fn check_iterations(period: f64) -> u32 {
    // Saturating cast: NaN gives 0, then the minimum.
    let proportional = (period * ITERATIONS_PER_SECOND) as u32;
    // Cannot panic: the bounds are constants in order.
    proportional.clamp(MIN_CHECK_ITERATIONS, CHECK_ITERATIONS)
}
/// The step of a line followed at full stride, as a fraction of the way.
const FULL_STEP: f64 = 1.0 / LINE_SAMPLES as f64;
/// The smallest step tried, as a fraction of the way.
const MIN_STEP: f64 = 1.0 / (8 * LINE_SAMPLES) as f64;
/// The smallest step tried where a joint moves more than [`MAX_JOINT_STEP`]: a swing near a
/// singularity is followed in steps this short, as the tick follows it.
const MIN_JUMP_STEP: f64 = MIN_STEP / 8.0;
/// Iterations of one tracking solve in the check at most.
const CHECK_SOLVE_ITERATIONS: u16 = 10;
/// A joint this close to a limit in a non-converged solution is taken as what stopped it.
const PINNED: f64 = 1e-9;

/// The checker of one request: the arm's kinematics, IK settings, workspace, the pose error
/// below which a set-point counts as reached (the tick's), and the IK iterations left.
pub(super) struct Reach<'a> {
    pub chain: &'a Chain,
    pub ik: &'a IkConfig,
    pub workspace: &'a Workspace,
    pub tolerance: f64,
    pub iterations_left: u32,
    /// The Cartesian speed limits (x, y, z, rx, ry, rz): how fast the line is planned.
    pub speed: &'a [f64; 6],
    /// The Cartesian acceleration limits (x, y, z, rx, ry, rz): how fast it speeds up.
    pub acceleration: &'a [f64; 6],
    /// The joints' rate limits.
    pub max_rate: &'a Joints,
    /// The joints' acceleration limits.
    pub max_acceleration: &'a Joints,
    /// The arm's body: each point of the line is checked for it.
    pub body: &'a Body,
}

/// The most a joint may move (rad, or m) in one step of the check. The nearest IK solution
/// of a pose a step ahead is not always the one the tick reaches by following the line: where
/// the line passes close to a singularity (the wrist centre near joint 1's axis), the tick
/// swings a joint through up to half a turn while the nearest solution lies on another branch,
/// a small step away. A step in which a joint moves more than this is retried shorter, and one
/// that still does at 1/1024 of the line is refused as a jump.
pub const MAX_JOINT_STEP: f64 = 0.25;

impl Reach<'_> {
    /// The tick's IK settings with at most [`CHECK_SOLVE_ITERATIONS`] per solve: a step of a
    /// sixteenth of the line converges in a few, and a failing one costs less.
    fn solve_config(&self) -> IkConfig {
        IkConfig {
            tracking_iterations: self.ik.tracking_iterations.min(CHECK_SOLVE_ITERATIONS),
            ..*self.ik
        }
    }

    /// Tracking IK from the point `from` to the pose of `to`, within the limits and the
    /// tolerance, written to `to`'s joints and angles; else why not.
    fn solve(&mut self, from: &Reached, to: &mut Reached, at: PathPoint) -> Result<(), Refusal> {
        let unreachable = Refusal::Unreachable(at);
        // Read in place: moving the answer out of its `Result` copied it.
        let config = self.solve_config();
        let angles = (&from.angles, &mut to.angles);
        let outcome =
            (self.chain).solve_tracking_from(&to.pose, (&from.q, &from.pose), &config, angles);
        let Ok(result) = &outcome else {
            return Err(unreachable);
        };
        let s = result.solution();
        self.iterations_left = self.iterations_left.saturating_sub(s.iterations);
        to.q = s.q;
        if s.position_error <= self.tolerance && s.orientation_error <= self.tolerance {
            return Ok(());
        }
        // The bounded descent stops joints exactly at their limits: one that sits there is
        // what kept the solution from the target.
        Err(pinned_joint(self.chain, &s.q, at).map_or(unreachable, Refusal::OutsideJointLimits))
    }
}

/// A line that passed the check: the joints at its end, and the duration to plan it for.
#[derive(Clone, Copy, Debug)]
pub(super) struct Checked {
    /// The joints at the goal.
    pub q: Joints,
    /// The least duration (s) to plan the line for ([`planned_duration`]).
    pub duration: f64,
}

/// A point of the line: the joints there, their pose (which spares the next solve the FK), and
/// their angles if a closed-form solve gave them (which spares it their `sincos`).
#[derive(Clone, Copy, Debug)]
struct Reached {
    q: Joints,
    pose: Frame,
    angles: SeedAngles,
}

/// A joint (numbered from 1) that cannot make a step of the check as the tick would.
enum Fault {
    /// It would need more than `ik.line_slowdown` times its rate limit at the line's cruise
    /// speed.
    Rate(u8),
    /// It would move more than [`MAX_JOINT_STEP`]: a jump to another branch, or a swing
    /// near a singularity.
    Jump(u8),
}

/// The first joint that cannot move from `q` to `next` in `time` (s) at `slowdown` times
/// `max_rate`, a jump first (a NaN is a jump).
fn fault(q: &Joints, next: &Joints, max_rate: &Joints, time: f64, slowdown: f64) -> Option<Fault> {
    let number = |joint: usize| u8::try_from(joint.saturating_add(1)).unwrap_or(u8::MAX);
    let moved = q.iter().zip(next.iter()).map(|(a, b)| libm::fabs(b - a));
    if let Some(joint) = moved.clone().position(|m| m.is_nan() || m > MAX_JOINT_STEP) {
        return Some(Fault::Jump(number(joint)));
    }
    moved
        .zip(max_rate.iter())
        .position(|(m, rate)| m > slowdown * rate * time)
        .map(|joint| Fault::Rate(number(joint)))
}

/// How sharply a line's profile moves along the way (fractions of it per second squared) when
/// stretched to last `D` s: no more than `acceleration / D²` (a trapezoid stretched in time),
/// and no faster than `2 / D` (a triangle's peak).
#[derive(Clone, Copy, Debug)]
struct Shape {
    acceleration: f64,
}

/// A bound on `(D · peak speed)²` of a stretched trapezoid, over the way: a triangle's.
const SPEED_SQUARED: f64 = 4.0;

impl Shape {
    /// The shape of the generator's trapezoids for a line by `delta` (x, y, z, rx, ry, rz)
    /// within the Cartesian `speed` and `acceleration` limits. With path limits `V` and `A`
    /// (fractions of the way, those of the most binding axis of each group, as
    /// [`StraightLine`]), a trapezoid's `A · T²` is `A / V² + 2 + V² / A`, at most
    /// `3 + A / V²` (`V² < A`), and `A / V²` at most `a_k · |δ_k| / v_k²` of the axis that binds
    /// `V`; a triangle's is 4.
    ///
    /// [`StraightLine`]: super::straight_line::StraightLine
    fn of(delta: &[f64; 6], speed: &[f64; 6], acceleration: &[f64; 6]) -> Self {
        let steep = delta
            .iter()
            .zip(speed.iter().zip(acceleration))
            .map(|(d, (v, a))| a * libm::fabs(*d) / (v * v))
            .fold(0.0, f64::max);
        Self {
            acceleration: (3.0 + steep).max(4.0),
        }
    }

    /// The least `D²` (s²) for which the step of `h` of the way from `q` to `next` needs no
    /// joint's acceleration beyond its `max_acceleration`: `(|q'| · a + |q''| · v²) / D²`, with
    /// `q'` the step's rate of change along the way and `q''` its change from the step before
    /// (`slope`, none at the first step; left there for the next). A NaN is infinite. Also
    /// how long (s) the whole line would last at a constant speed at which the step needs no
    /// joint faster than its `max_rate` (`|Δq| / (max_rate · h)`), and whether some joint's
    /// rate fell by more than half from the step before.
    fn needs(
        &self,
        slope: &mut Option<[f64; MAX_JOINTS]>,
        (q, next): (&Joints, &Joints),
        h: f64,
        (max_rate, max_acceleration): (&Joints, &Joints),
    ) -> (f64, f64, bool) {
        let first = slope.is_none();
        let before = slope.get_or_insert([0.0; MAX_JOINTS]);
        let (mut fastest, mut most, mut slowed) = (0.0_f64, 0.0_f64, false);
        let limits = max_rate.iter().zip(max_acceleration.iter());
        let joints = q.iter().zip(next.iter()).zip(limits);
        for (((a, b), (max_rate, limit)), before) in joints.zip(before.iter_mut()) {
            let rate = (b - a) / h;
            let bend = if first {
                0.0
            } else {
                libm::fabs(rate - *before) / h
            };
            slowed |= !first && libm::fabs(*before) > 2.0 * libm::fabs(rate);
            *before = rate;
            let need = (libm::fabs(rate) * self.acceleration + bend * SPEED_SQUARED) / limit;
            let fast = libm::fabs(rate) / max_rate;
            // Written so that a NaN counts as infinite.
            most = if need.is_nan() {
                f64::INFINITY
            } else {
                most.max(need)
            };
            fastest = if fast.is_nan() {
                f64::INFINITY
            } else {
                fastest.max(fast)
            };
        }
        (fastest, most, slowed)
    }
}

/// The share of its `max_rate` a joint may need at a checked step at the line's planned peak
/// speed ([`planned_duration`]): the rest is left for what happens between the checked points,
/// where the tick's time scale slows the motion down if it must.
const RATE_SHARE: f64 = 0.9;

/// The duration (s) to plan a line for so that at its peak speed no checked step needs more
/// than [`RATE_SHARE`] of a joint's `max_rate`: `min_duration` (≥ 0, the client's) if that is
/// slow enough, else longer. `cruise`: how long the line lasts at the Cartesian speed limits
/// (s); `needs`: the largest of its steps' rate needs ([`Shape::needs`]). A profile stretched to a duration
/// `D` peaks at no more than twice the average speed (at `2/D` of the way per second, the
/// triangle), and no profile exceeds the speed limits (`1/cruise`).
fn planned_duration(min_duration: f64, cruise: f64, needs: f64) -> f64 {
    let peak = if min_duration > 0.0 {
        (2.0 / min_duration).min(1.0 / cruise)
    } else {
        1.0 / cruise
    };
    if needs <= 0.0 || peak * needs <= RATE_SHARE {
        min_duration
    } else {
        min_duration.max(2.0 * needs / RATE_SHARE)
    }
}

/// The first joint of `q` at (within [`PINNED`]) or beyond one of its limits.
fn pinned_joint(chain: &Chain, q: &[f64], at: PathPoint) -> Option<JointBound> {
    first_bound(chain, q, at, |past| past >= -PINNED)
}

/// The first joint of `q` beyond one of its limits, if any (for joint goals).
pub(super) fn joint_beyond_limit(chain: &Chain, q: &[f64]) -> Option<JointBound> {
    first_bound(chain, q, PathPoint::Goal, |past| past > 0.0)
}

/// The first joint and limit for which `hit(how far q is past the limit)` holds (negative:
/// inside).
fn first_bound(
    chain: &Chain,
    q: &[f64],
    at: PathPoint,
    hit: impl Fn(f64) -> bool,
) -> Option<JointBound> {
    q.iter()
        .zip(chain.min().iter().zip(chain.max()))
        .enumerate()
        .find_map(|(joint, (&v, (&lo, &hi)))| {
            if hit(lo - v) {
                Some(JointBound::new(joint, false, lo, at))
            } else if hit(v - hi) {
                Some(JointBound::new(joint, true, hi, at))
            } else {
                None
            }
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_step_faults_on_a_jump_first_then_on_a_rate() {
        let step = |a: f64, b: f64| Joints::from_slice(&[a, b]).unwrap();
        let (rate, q) = (step(0.2, 0.2), step(0.0, 1.0));
        // 0.2 rad/s for 1 s: up to 20 rad slowed down 100 times, but never more than 0.25 a
        // step.
        assert!(fault(&q, &step(0.25, 1.0), &rate, 1.0, 100.0).is_none());
        assert!(matches!(
            fault(&q, &step(0.1, 1.26), &rate, 1.0, 100.0),
            Some(Fault::Jump(2))
        ));
        assert!(matches!(
            fault(&q, &step(0.21, 1.0), &rate, 0.01, 100.0),
            Some(Fault::Rate(1))
        ));
        assert!(matches!(
            fault(&q, &step(0.21, f64::NAN), &rate, 0.01, 100.0),
            Some(Fault::Jump(2))
        ));
        // A robot file that allows no slowing down (ik.line_slowdown = 1): 0.21 rad in 1 s at
        // 0.2 rad/s is too fast.
        assert!(fault(&q, &step(0.2, 1.0), &rate, 1.0, 1.0).is_none());
        assert!(matches!(
            fault(&q, &step(0.21, 1.0), &rate, 1.0, 1.0),
            Some(Fault::Rate(1))
        ));
    }

    #[test]
    fn a_line_is_planned_slower_only_where_its_joints_need_it() {
        // 10 s at the Cartesian limits; a step needing the whole line to last 5 s at the
        // joints' rates is fine (0.5 of the rate at the peak), one needing 18 s is not: then
        // planned for 2 × 18 / 0.9 = 40 s, the triangle's peak at twice the average.
        assert_eq!(planned_duration(0.0, 10.0, 5.0), 0.0);
        assert!((planned_duration(0.0, 10.0, 18.0) - 40.0).abs() < 1e-9);
        // A client's 50 s is slow enough already (peak 2/50 of the way per second).
        assert_eq!(planned_duration(50.0, 10.0, 18.0), 50.0);
        assert_eq!(planned_duration(0.0, 0.0, 0.0), 0.0);
    }

    #[test]
    fn a_line_s_shape_is_its_stretched_trapezoid() {
        let (v, a) = (
            [0.1, 0.1, 0.1, 0.5, 0.5, 0.5],
            [0.1, 1.0, 1.0, 1.0, 1.0, 1.0],
        );
        // 0.1 m along x: a triangle (1 way/s² never reaches 1 way/s).
        let shape = Shape::of(&[0.1, 0.0, 0.0, 0.0, 0.0, 0.0], &v, &a);
        assert_eq!(shape.acceleration, 4.0);
        // 1 m along y: 0.1 way/s after 0.1 s, 10.1 s in all: A · T² = 102.01 ≤ 103.
        let shape = Shape::of(&[0.0, 1.0, 0.0, 0.0, 0.0, 0.0], &v, &a);
        assert!((shape.acceleration - 103.0).abs() < 1e-9);
        // A joint changing at 0.5 rad per way over a tenth of it, then at 0.6 (a change of 1
        // per way²): at 1 rad/s² its steps need 0.5 · 103 and 0.6 · 103 + 1 · 4 s².
        let joints = |v: f64| Joints::from_slice(&[v]).unwrap();
        let limit = joints(1.0);
        let mut slope = None;
        let limits = (&limit, &limit);
        let (fast, first, _) = shape.needs(&mut slope, (&joints(0.0), &joints(0.05)), 0.1, limits);
        assert!((fast - 0.5).abs() < 1e-12);
        assert!((first - 0.5 * 103.0).abs() < 1e-9);
        let (_, next, slowed) =
            shape.needs(&mut slope, (&joints(0.05), &joints(0.11)), 0.1, limits);
        assert!((next - (0.6 * 103.0 + 4.0)).abs() < 1e-9, "{next}");
        assert!(!slowed);
        // Then at 0.2 per way: its rate fell by more than half.
        let (_, _, slowed) = shape.needs(&mut slope, (&joints(0.11), &joints(0.13)), 0.1, limits);
        assert!(slowed);
    }

    #[test]
    fn the_budget_follows_the_control_period_within_its_bounds() {
        assert_eq!(check_iterations(0.01944), CHECK_ITERATIONS);
        assert_eq!(check_iterations(0.00504), 201);
        assert_eq!(check_iterations(0.0001), MIN_CHECK_ITERATIONS);
        assert_eq!(check_iterations(f64::NAN), MIN_CHECK_ITERATIONS);
        assert_eq!(check_iterations(f64::INFINITY), CHECK_ITERATIONS);
    }
}
