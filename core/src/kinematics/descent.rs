//! One descent of the numeric solver: damped least squares with joint limits as an active set.
//!
//! Each iteration takes the damped least-squares step `Δq = (JᵀJ + λI)⁻¹Jᵀe = Jᵀ(JJᵀ + λI)⁻¹e`
//! (solved as the 6×6 system, whatever the joint count) for the pose error `e` (position error and
//! rotation vector, base frame). The damping `λ = ½|e|² + λ_min` (Sugihara's error-damped
//! Levenberg–Marquardt) takes cautious steps far from the goal or near a singularity and
//! becomes a Newton step close to the solution, so convergence to 1e-9 is quadratic there.
//!
//! Joint limits: KDL's `ChainIkSolverPos_NR_JL`, which the seed configured, clamps after every
//! Newton step. A joint pinned at its limit then keeps absorbing its share of the step and the
//! solver stalls. Here a joint that sits at a limit and whose step points outwards is *locked*
//! for that iteration (its column is removed and the step re-solved), so the other joints take
//! over; a joint that crosses a limit is stopped at it. The global search also wraps revolute
//! joints by 2π where the range allows, and abandons an attempt that stops making progress.

use nalgebra::Vector6;

use super::chain::{Axes, Chain};
use super::evaluation::LastEvaluation;
use super::ik::{IkResult, IkSolution};
use super::jacobian::{Jacobian, JointVector, damped_least_squares};
use crate::MAX_JOINTS;
use crate::math::{self, Frame, Joints};
use crate::saturate::saturate;

/// Damping floor: keeps every system positive definite, small enough that steps near the
/// solution are Newton steps.
const LAMBDA_MIN: f64 = 1e-9;
/// A joint within this distance of a limit counts as sitting on it.
const AT_LIMIT: f64 = 1e-12;
/// A global attempt must halve its error every this many steps, or it is abandoned.
const PROGRESS_WINDOW: u32 = 5;
/// Steps smaller than this (∞-norm) without convergence mean a local minimum.
const STALL_STEP: f64 = 1e-10;
/// Most steps that take a near solution to full precision ([`Chain::sharpen`]): within
/// ~0.05 rad of two singularities at once they take up to about 60.
const SHARPEN_STEPS: usize = 64;
/// The least damping of those steps: only keeps the system positive definite.
const SHARPEN_DAMPING: f64 = 1e-24;
/// Factors of that damping after a step that succeeds and one that fails.
const SHARPEN_FALL: f64 = 1e-3;
const SHARPEN_RISE: f64 = 100.0;
/// Damping at which those steps are too short to matter: rounding stops them.
const SHARPEN_GIVE_UP: f64 = 1.0;
/// An error (m and rad, together) at which a solution counts as exact: rounding is near.
const SHARP: f64 = 1e-14;

/// How a descent treats the joint limits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Bounds {
    /// Ignored: a first attempt whose answer is checked afterwards.
    Free,
    /// Enforced (active set, clamping).
    Enforced,
    /// Enforced, and revolute joints may also wrap by 2π (the global search).
    Wrapping,
}

/// The result of one descent from one starting point.
pub(super) struct Descent {
    /// The best pose visited; its `iterations` is this descent's `steps`.
    pub best: IkSolution,
    pub converged: bool,
    /// Newton steps actually taken (the budget this descent spent).
    pub steps: u32,
}

impl Chain {
    /// Damped Newton iterations from `q` (its pose and axes reused from `last` if evaluated
    /// there; every evaluation is left there); returns the best pose visited.
    pub(super) fn descend(
        &self,
        target: &Frame,
        mut q: [f64; MAX_JOINTS],
        iterations: u16,
        tolerance: f64,
        (bounds, last): (Bounds, &mut LastEvaluation),
        on_step: &mut impl FnMut(),
    ) -> Descent {
        // The best pose as plain values; the `IkSolution` (a `Joints` inside) is built once, at
        // the end: moving it every iteration cost the Cortex-M7 more than the step's maths.
        let mut best = Pose {
            q,
            position_error: f64::INFINITY,
            orientation_error: f64::INFINITY,
        };
        // Reused across iterations: on the Cortex-M7 rebuilding it costs more than the maths.
        let mut jacobian = Jacobian::zeros();
        let mut steps = 0;
        let mut checkpoint = f64::INFINITY;
        for it in 0..=u32::from(iterations) {
            let tool = last.at(self, &q);
            let e = math::diff(&tool, target);
            let pose = Pose {
                q,
                position_error: e.fixed_rows::<3>(0).norm(),
                orientation_error: e.fixed_rows::<3>(3).norm(),
            };
            // The first evaluation always counts: with a huge target every score is infinite.
            if it == 0 || pose.score() < best.score() {
                best = pose;
            }
            if pose.position_error < tolerance && pose.orientation_error < tolerance {
                return Descent {
                    best: pose.solution(self.dof(), steps),
                    converged: true,
                    steps,
                };
            }
            if it == u32::from(iterations) {
                break;
            }
            let energy = 0.5 * e.norm_squared();
            self.jacobian_into(last.axes(), &tool.translation.vector, &mut jacobian);
            let step = self.step(&jacobian, &e, energy + LAMBDA_MIN, &q, bounds);
            steps += 1;
            on_step();
            self.apply(&mut q, &step, bounds);
            if step.amax() < STALL_STEP {
                break;
            }
            // A global attempt that has not halved its error in the last PROGRESS_WINDOW
            // steps is in a local minimum or pinned on a limit: a new seed is a better use
            // of the budget.
            if bounds == Bounds::Wrapping && steps % PROGRESS_WINDOW == 0 {
                let now = best.score();
                if now > 0.5 * checkpoint {
                    break;
                }
                checkpoint = now;
            }
        }
        Descent {
            best: best.solution(self.dof(), steps),
            converged: false,
            steps,
        }
    }

    /// Levenberg–Marquardt steps from `q`, near a solution, whose damping falls from
    /// [`LAMBDA_MIN`] towards none while they succeed and rises again when a step fails to
    /// shrink the error or leaves the limits; `q` is the best pose reached. Near a singularity
    /// the descent's steps, damped by [`LAMBDA_MIN`] as much as the Jacobian's smallest
    /// squared singular value, crawl: a solution that passes a 1e-9 check can lie 1e-5 rad
    /// from the exact one, and a descent within 1e-7 of the target can run out of steps.
    pub(super) fn sharpen(&self, target: &Frame, q: &mut Joints) {
        let mut x = *q.as_array();
        let (mut axes, mut jacobian) = (Axes::default(), Jacobian::zeros());
        let mut tool = self.tool_and_axes(&x, &mut axes);
        let mut e = math::diff(&tool, target);
        self.jacobian_into(&axes, &tool.translation.vector, &mut jacobian);
        let mut lambda = LAMBDA_MIN;
        let mut trial_axes = Axes::default();
        for _ in 0..SHARPEN_STEPS {
            let error = e.norm_squared();
            if error < SHARP * SHARP || lambda > SHARPEN_GIVE_UP {
                break;
            }
            let none = [false; MAX_JOINTS];
            let Some(dq) = damped_least_squares(&jacobian, self.dof(), &e, lambda, &none) else {
                break;
            };
            let mut trial = x;
            for (t, d) in trial.iter_mut().zip(dq.iter()) {
                *t += d;
            }
            let reached = self.tool_and_axes(&trial, &mut trial_axes);
            let trial_e = math::diff(&reached, target);
            let inside = self.within_limits(trial.get(..self.dof()).unwrap_or(&[]));
            if inside && trial_e.norm_squared() < error {
                (x, tool, e, axes) = (trial, reached, trial_e, trial_axes);
                self.jacobian_into(&axes, &tool.translation.vector, &mut jacobian);
                lambda = (lambda * SHARPEN_FALL).max(SHARPEN_DAMPING);
            } else {
                lambda *= SHARPEN_RISE;
            }
        }
        for (v, x) in q.iter_mut().zip(&x) {
            *v = *x;
        }
    }

    /// One damped least-squares step with the joint limits as an active set (a small bounded
    /// least-squares problem).
    ///
    /// A joint on a limit whose step points outwards is locked and the step re-solved without
    /// it; a locked joint whose multiplier says the remaining error would shrink if it moved
    /// inwards (`Jᵀ(e − J·dq)` points inwards) is released again. KDL's NR_JL only clamps, so a
    /// joint pinned on a limit keeps absorbing its share of every step and the solver stalls.
    fn step(
        &self,
        j: &Jacobian,
        e: &Vector6<f64>,
        lambda: f64,
        q: &[f64; MAX_JOINTS],
        bounds: Bounds,
    ) -> JointVector {
        let n = self.dof();
        let (min, max) = self.limits();
        let pushes_out = |qi: f64, lo: f64, hi: f64, push: f64| {
            (qi >= hi - AT_LIMIT && push > 0.0) || (qi <= lo + AT_LIMIT && push < 0.0)
        };
        let mut locked = [false; MAX_JOINTS];
        let mut dq = JointVector::zeros();
        // Every pass changes the locked set; 2n + 2 passes bound even an add/drop cycle.
        for _ in 0..2 * n + 2 {
            // A locked joint is a zeroed column of the Jacobian.
            let Some(solved) = damped_least_squares(j, n, e, lambda, &locked) else {
                return JointVector::zeros();
            };
            dq = solved;
            if bounds == Bounds::Free {
                break;
            }
            let mut changed = false;
            let joints = q.iter().zip(dq.iter()).zip(min.iter().zip(max)).take(n);
            for (((qi, di), (lo, hi)), lock) in joints.zip(locked.iter_mut()) {
                if !*lock && pushes_out(*qi, *lo, *hi, *di) {
                    *lock = true;
                    changed = true;
                }
            }
            if !changed && locked.iter().any(|l| *l) {
                let multiplier = j.tr_mul(&(e - j * dq));
                let joints = q
                    .iter()
                    .zip(multiplier.iter())
                    .zip(min.iter().zip(max))
                    .take(n);
                for (((qi, mi), (lo, hi)), lock) in joints.zip(locked.iter_mut()) {
                    if *lock && !pushes_out(*qi, *lo, *hi, *mi) {
                        *lock = false;
                        changed = true;
                    }
                }
            }
            if !changed {
                break;
            }
        }
        dq
    }

    /// `q += dq`; with bounds, revolute joints wrapped by 2π into range when allowed, then
    /// clamped.
    fn apply(&self, q: &mut [f64; MAX_JOINTS], dq: &JointVector, bounds: Bounds) {
        const TAU: f64 = core::f64::consts::TAU;
        let (min, max) = self.limits();
        let joints = q
            .iter_mut()
            .zip(dq.iter())
            .zip(min.iter().zip(max))
            .enumerate();
        for (i, ((qi, di), (lo, hi))) in joints.take(self.dof()) {
            let mut v = *qi + di;
            if bounds == Bounds::Free {
                *qi = v;
                continue;
            }
            if bounds == Bounds::Wrapping && !self.is_prismatic(i) && (v < *lo || v > *hi) {
                let turns = libm::round((0.5 * (lo + hi) - v) / TAU);
                let wrapped = v + turns * TAU;
                if *lo <= wrapped && wrapped <= *hi {
                    v = wrapped;
                }
            }
            *qi = saturate(v, *lo, *hi);
        }
    }
}

impl Descent {
    pub(super) fn into_result(self) -> IkResult {
        if self.converged {
            IkResult::Converged(self.best)
        } else {
            IkResult::NotConverged(self.best)
        }
    }
}

/// A pose visited by a descent: joint values and their errors.
#[derive(Clone, Copy)]
struct Pose {
    q: [f64; MAX_JOINTS],
    position_error: f64,
    orientation_error: f64,
}

impl Pose {
    /// The seed's mixed metric: metres plus radians.
    fn score(&self) -> f64 {
        self.position_error + self.orientation_error
    }

    /// The solution of `n` joints reached after `steps` Newton steps.
    fn solution(&self, n: usize, steps: u32) -> IkSolution {
        let mut q = Joints::zeros(n);
        for (j, v) in q.iter_mut().zip(self.q) {
            *j = v;
        }
        IkSolution {
            q,
            iterations: steps,
            position_error: self.position_error,
            orientation_error: self.orientation_error,
        }
    }
}
