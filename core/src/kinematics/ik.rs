//! Inverse position kinematics: damped least squares with joint limits as an active set.
//!
//! Each iteration solves `(JᵀJ + λI) Δq = Jᵀe` for the pose error `e` (position error and
//! rotation vector, base frame). The damping `λ = ½|e|² + λ_min` (Sugihara's error-damped
//! Levenberg–Marquardt) takes cautious steps far from the goal or near a singularity and
//! becomes a Newton step close to the solution, so convergence to 1e-9 is quadratic there.
//!
//! Joint limits: KDL's `ChainIkSolverPos_NR_JL`, which the seed configured, clamps after every
//! Newton step. A joint pinned at its limit then keeps absorbing its share of the step and the
//! solver stalls. Here a joint that sits at a limit and whose step points outwards is *locked*
//! for that iteration (its column is removed and the step re-solved), so the other joints take
//! over; a joint that crosses a limit is stopped at it. The global solver also wraps revolute
//! joints by 2π where the range allows, and restarts from deterministic random seeds.

use super::chain::{Axes, Chain};
use super::jacobian::Jacobian;
use super::joints::Joints;
use super::linalg;
use crate::MAX_JOINTS;
use crate::config::IkConfig;
use crate::math::Frame;
use crate::rng::SplitMix64;

/// Damping floor: keeps every system positive definite, small enough that steps near the
/// solution are Newton steps.
const LAMBDA_MIN: f64 = 1e-9;
/// A joint within this distance of a limit counts as sitting on it.
const AT_LIMIT: f64 = 1e-12;
/// Iterations of one global attempt before it restarts from a new random seed.
const ATTEMPT_ITERATIONS: u16 = 30;
/// Steps smaller than this (∞-norm) without convergence mean a local minimum.
const STALL_STEP: f64 = 1e-10;

/// An IK answer: joint values, how many iterations it took and how far from the target it is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IkSolution {
    /// Joint values, always within the joint limits.
    pub q: Joints,
    /// Newton iterations used (over all restarts for the global solver).
    pub iterations: u32,
    /// Distance from the target position (m).
    pub position_error: f64,
    /// Rotation angle from the target orientation (rad).
    pub orientation_error: f64,
}

/// The outcome of an IK solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum IkResult {
    /// Within the tolerance on both position and orientation.
    Converged(IkSolution),
    /// The iteration budget ran out; this is the best pose found.
    NotConverged(IkSolution),
}

impl IkResult {
    /// The solution, converged or best effort.
    pub fn solution(&self) -> &IkSolution {
        match self {
            Self::Converged(s) | Self::NotConverged(s) => s,
        }
    }

    /// True if the solve converged.
    pub fn is_converged(&self) -> bool {
        matches!(self, Self::Converged(_))
    }
}

/// Why an IK request was refused before solving.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IkError {
    /// The seed's length differs from the chain's number of joints.
    WrongJointCount,
    /// The seed holds NaN or infinite values.
    NonFiniteSeed,
    /// The target frame holds NaN or infinite values.
    NonFiniteTarget,
}

impl core::fmt::Display for IkError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::WrongJointCount => "seed length differs from the number of joints",
            Self::NonFiniteSeed => "seed holds NaN or infinite values",
            Self::NonFiniteTarget => "target holds NaN or infinite values",
        })
    }
}

/// The seed's divergence guard (spec §3.5): true if the solved pose is farther from the target
/// than the current pose by more than `margin` (metric: metres + radians). A diverging solution
/// must not be commanded; the arm holds instead.
pub fn diverges(target: &Frame, solved: &Frame, current: &Frame, margin: f64) -> bool {
    target.dist(solved) - target.dist(current) > margin
}

/// The result of one descent from one starting point.
/// How a descent treats the joint limits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Bounds {
    /// Ignored: a first attempt whose answer is checked afterwards.
    Free,
    /// Enforced (active set, clamping).
    Enforced,
    /// Enforced, and revolute joints may also wrap by 2π (the global search).
    Wrapping,
}

struct Descent {
    best: IkSolution,
    converged: bool,
}

impl Chain {
    /// Tracking IK: a few damped Newton steps from a nearby `seed`, typically the previous
    /// tick's solution. Never wraps joints by 2π, so the result stays on the seed's branch and
    /// a commanded trajectory cannot jump a whole turn.
    ///
    /// The limits only matter when the nearby solution violates them, so the first descent
    /// ignores them and its answer is checked; only if it breaks a limit (or does not converge)
    /// does a bounded descent from the same seed follow. An unbounded Newton path may pass
    /// outside a limit on its way to a solution inside; a bounded one can then end on the
    /// limit in a local minimum (seeds a few millimetres inside UR5's ±2π limits did).
    pub fn solve_tracking(
        &self,
        target: &Frame,
        seed: &[f64],
        config: &IkConfig,
    ) -> Result<IkResult, IkError> {
        let q = self.prepare(target, seed)?;
        let (iterations, tolerance) = (config.tracking_iterations, config.tolerance);
        let free = self.descend(target, q, iterations, tolerance, Bounds::Free);
        let mut used = free.best.iterations;
        if free.converged {
            if self.within_limits(&free.best.q) {
                return Ok(IkResult::Converged(free.best));
            }
            // Converged beyond a limit: near a stretched or folded singularity the nearby
            // branches mirror each other about the joint value there, so the solution
            // reflected about the limit seeds the bounded descent well.
            let mirrored = self.reflected_into_limits(&free.best.q);
            let retry = self.descend(target, mirrored, iterations, tolerance, Bounds::Enforced);
            used += retry.best.iterations;
            if retry.converged {
                let mut best = retry.best;
                best.iterations = used;
                return Ok(IkResult::Converged(best));
            }
        }
        let mut bounded = self.descend(target, q, iterations, tolerance, Bounds::Enforced);
        bounded.best.iterations += used;
        Ok(bounded.into_result())
    }

    /// Global IK: descends from `seed`, then from deterministic random configurations drawn
    /// with `rng_seed`, until one converges within the limits or `config.global_iterations`
    /// iterations are spent. The same inputs always give the same answer.
    pub fn solve_global(
        &self,
        target: &Frame,
        seed: &[f64],
        config: &IkConfig,
        rng_seed: u64,
    ) -> Result<IkResult, IkError> {
        let start = self.prepare(target, seed)?;
        let mut q = start;
        let mut rng = SplitMix64::new(rng_seed);
        let mut budget = config.global_iterations;
        let mut best: Option<IkSolution> = None;
        let mut used = 0u32;
        // Each attempt spends at least one iteration, so this bound is never the binding one.
        for _ in 0..config.global_iterations {
            let limit = budget.min(ATTEMPT_ITERATIONS);
            let descent = self.descend(target, q, limit, config.tolerance, Bounds::Wrapping);
            used += descent.best.iterations;
            budget = budget.saturating_sub(descent.best.iterations.max(1) as u16);
            let mut found = descent.best;
            found.iterations = used;
            if descent.converged {
                return Ok(IkResult::Converged(found));
            }
            if best.is_none_or(|b| score(&found) < score(&b)) {
                best = Some(found);
            }
            if budget == 0 {
                break;
            }
            q = self.random_configuration(&mut rng);
        }
        // Only a zero budget leaves no attempt: then the answer is the (clamped) seed itself.
        let mut best = best.unwrap_or_else(|| {
            self.descend(target, start, 0, config.tolerance, Bounds::Wrapping)
                .best
        });
        best.iterations = used;
        Ok(IkResult::NotConverged(best))
    }

    /// `q` with every joint beyond a limit reflected about that limit (then clamped).
    fn reflected_into_limits(&self, q: &[f64]) -> [f64; MAX_JOINTS] {
        let mut out = [0.0; MAX_JOINTS];
        let (min, max) = self.limits();
        for ((o, v), (lo, hi)) in out.iter_mut().zip(q).zip(min.iter().zip(max)) {
            let reflected = if *v > *hi {
                2.0 * hi - v
            } else if *v < *lo {
                2.0 * lo - v
            } else {
                *v
            };
            *o = reflected.clamp(*lo, *hi);
        }
        out
    }

    /// Validates the inputs and returns the seed clamped into the limits.
    fn prepare(&self, target: &Frame, seed: &[f64]) -> Result<[f64; MAX_JOINTS], IkError> {
        if !target.is_finite() {
            return Err(IkError::NonFiniteTarget);
        }
        if seed.len() != self.dof() {
            return Err(IkError::WrongJointCount);
        }
        let mut q = [0.0; MAX_JOINTS];
        let (min, max) = self.limits();
        for ((v, s), (lo, hi)) in q.iter_mut().zip(seed).zip(min.iter().zip(max)) {
            if !s.is_finite() {
                return Err(IkError::NonFiniteSeed);
            }
            *v = s.clamp(*lo, *hi);
        }
        Ok(q)
    }

    /// A configuration drawn uniformly within the limits (revolute ranges capped at ±π about
    /// their centre: a wider range only repeats the same poses).
    fn random_configuration(&self, rng: &mut SplitMix64) -> [f64; MAX_JOINTS] {
        let mut q = [0.0; MAX_JOINTS];
        let (min, max) = self.limits();
        for (i, (v, (lo, hi))) in q.iter_mut().zip(min.iter().zip(max)).enumerate() {
            let (lo, hi) = if self.is_prismatic(i) {
                (*lo, *hi)
            } else {
                let mid = 0.5 * (lo + hi);
                (
                    lo.max(mid - core::f64::consts::PI),
                    hi.min(mid + core::f64::consts::PI),
                )
            };
            *v = rng.uniform(lo, hi);
        }
        q
    }

    /// Damped Newton iterations from `q`; returns the best pose visited.
    fn descend(
        &self,
        target: &Frame,
        mut q: [f64; MAX_JOINTS],
        iterations: u16,
        tolerance: f64,
        bounds: Bounds,
    ) -> Descent {
        let n = self.dof();
        let mut best = IkSolution {
            q: Joints::zeros(n),
            iterations: 0,
            position_error: f64::INFINITY,
            orientation_error: f64::INFINITY,
        };
        // Reused across iterations: on the Cortex-M7 rebuilding them costs more than the maths.
        let mut axes = Axes::default();
        let mut jacobian = Jacobian::zero(n);
        for it in 0..=u32::from(iterations) {
            let tool = self.tool_and_axes(&q, &mut axes);
            let e = tool.diff(target);
            let solution = IkSolution {
                q: joints_of(&q, n),
                iterations: it,
                position_error: e.linear.norm(),
                orientation_error: e.angular.norm(),
            };
            // The first evaluation always counts: with a huge target every score is infinite.
            if it == 0 || score(&solution) < score(&best) {
                best = solution;
            }
            if solution.position_error < tolerance && solution.orientation_error < tolerance {
                return Descent {
                    best: solution,
                    converged: true,
                };
            }
            if it == u32::from(iterations) {
                break;
            }
            let e = e.to_array();
            let energy = 0.5 * e.iter().map(|v| v * v).sum::<f64>();
            self.jacobian_into(&axes, tool.pos, &mut jacobian);
            let step = self.step(&jacobian, &e, energy + LAMBDA_MIN, &q, bounds);
            let largest = step.iter().fold(0.0f64, |m, v| m.max(libm::fabs(*v)));
            self.apply(&mut q, &step, bounds);
            if largest < STALL_STEP {
                best.iterations = it + 1;
                break;
            }
        }
        Descent {
            best,
            converged: false,
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
        e: &[f64; 6],
        lambda: f64,
        q: &[f64; MAX_JOINTS],
        bounds: Bounds,
    ) -> [f64; MAX_JOINTS] {
        let n = self.dof();
        let gradient = j.transpose_mul(e);
        let (min, max) = self.limits();
        let pushes_out = |qi: f64, lo: f64, hi: f64, push: f64| {
            (qi >= hi - AT_LIMIT && push > 0.0) || (qi <= lo + AT_LIMIT && push < 0.0)
        };
        let mut locked = [false; MAX_JOINTS];
        let mut a = [[0.0; MAX_JOINTS]; MAX_JOINTS];
        let mut dq = [0.0; MAX_JOINTS];
        // Every pass changes the locked set; 2n + 2 passes bound even an add/drop cycle.
        for _ in 0..2 * n + 2 {
            j.damped_gram_into(lambda, &locked, &mut a);
            for ((d, g), lock) in dq.iter_mut().zip(&gradient).zip(&locked) {
                *d = if *lock { 0.0 } else { *g };
            }
            if !linalg::cholesky_solve(&mut a, &mut dq, n) {
                return [0.0; MAX_JOINTS];
            }
            if bounds == Bounds::Free {
                break;
            }
            let mut changed = false;
            let joints = q.iter().zip(&dq).zip(min.iter().zip(max)).take(n);
            for (((qi, di), (lo, hi)), lock) in joints.zip(locked.iter_mut()) {
                if !*lock && pushes_out(*qi, *lo, *hi, *di) {
                    *lock = true;
                    changed = true;
                }
            }
            if !changed && locked.iter().any(|l| *l) {
                let mut residual = *e;
                for (r, m) in residual.iter_mut().zip(j.twist(&dq).to_array()) {
                    *r -= m;
                }
                let multiplier = j.transpose_mul(&residual);
                let joints = q.iter().zip(&multiplier).zip(min.iter().zip(max)).take(n);
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
    fn apply(&self, q: &mut [f64; MAX_JOINTS], dq: &[f64; MAX_JOINTS], bounds: Bounds) {
        const TAU: f64 = core::f64::consts::TAU;
        let (min, max) = self.limits();
        let joints = q.iter_mut().zip(dq).zip(min.iter().zip(max)).enumerate();
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
            *qi = v.clamp(*lo, *hi);
        }
    }
}

impl Descent {
    fn into_result(self) -> IkResult {
        if self.converged {
            IkResult::Converged(self.best)
        } else {
            IkResult::NotConverged(self.best)
        }
    }
}

/// The seed's mixed metric: metres plus radians.
fn score(s: &IkSolution) -> f64 {
    s.position_error + s.orientation_error
}

fn joints_of(q: &[f64; MAX_JOINTS], n: usize) -> Joints {
    let mut joints = Joints::zeros(n);
    joints.copy_from_slice(q.get(..n).unwrap_or(&[]));
    joints
}
