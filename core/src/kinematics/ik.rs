//! Inverse position kinematics: damped least squares with joint limits as an active set.
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
//! over; a joint that crosses a limit is stopped at it. The global solver also wraps revolute
//! joints by 2π where the range allows, and restarts from deterministic random seeds, early
//! when an attempt stops making progress.

use nalgebra::Vector6;

use super::chain::Chain;
use super::closed_form::{Misses, SeedAngles};
use super::evaluation::LastEvaluation;
use super::jacobian::{Jacobian, JointVector, damped_least_squares};
use crate::MAX_JOINTS;
use crate::config::IkConfig;
use crate::math::Joints;
use crate::math::{self, Frame};
use crate::rng::SplitMix64;
use crate::saturate::saturate;

/// The most a joint may move from the seed in a closed-form tracking solution (rad): beyond,
/// the seed's branch has no solution within the limits here.
pub const TRACKING_JUMP: f64 = 0.5;
/// Below this seed error (m + rad) tracking IK takes Newton steps even on a chain with a
/// closed form: from 3 mm they converge in two or three (about 9,500–14,000 Cortex-M7
/// instructions). Chosen when the closed form took about 13,500; it now takes about 6,300
/// (qemu-bench), but the control tick's rule is kept as it was.
const NEWTON_NEAR: f64 = 3e-3;
/// Damping floor: keeps every system positive definite, small enough that steps near the
/// solution are Newton steps.
const LAMBDA_MIN: f64 = 1e-9;
/// A joint within this distance of a limit counts as sitting on it.
const AT_LIMIT: f64 = 1e-12;
/// Iterations of one global attempt before it restarts from a new random seed.
const ATTEMPT_ITERATIONS: u16 = 30;
/// A global attempt must halve its error every this many steps, or it is abandoned.
const PROGRESS_WINDOW: u32 = 5;
/// Steps smaller than this (∞-norm) without convergence mean a local minimum.
const STALL_STEP: f64 = 1e-10;

/// An IK answer: joint values, how many iterations it took and how far from the target it is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IkSolution {
    /// Joint values, always within the joint limits.
    pub q: Joints,
    /// Newton iterations run (over all attempts), whichever pose was best.
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
    /// The chain belongs to no closed-form family (only the numeric solvers apply).
    NoClosedForm,
}

impl core::fmt::Display for IkError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::WrongJointCount => "seed length differs from the number of joints",
            Self::NonFiniteSeed => "seed holds NaN or infinite values",
            Self::NonFiniteTarget => "target holds NaN or infinite values",
            Self::NoClosedForm => "no closed-form inverse kinematics for this chain",
        })
    }
}

/// Empties `angles`, if kept: the answer they are left for is not a closed-form root's.
fn forget(angles: Option<&mut SeedAngles>) {
    if let Some(angles) = angles {
        *angles = SeedAngles::default();
    }
}

/// The seed's divergence guard (spec §3.5): true if the solved pose is farther from the target
/// than the current pose by more than `margin` (metric: metres + radians). A diverging solution
/// must not be commanded; the arm holds instead.
pub fn diverges(target: &Frame, solved: &Frame, current: &Frame, margin: f64) -> bool {
    math::dist(target, solved) - math::dist(target, current) > margin
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
    /// The best pose visited; its `iterations` is this descent's `steps`.
    best: IkSolution,
    converged: bool,
    /// Newton steps actually taken (the budget this descent spent).
    steps: u32,
}

impl Chain {
    /// Tracking IK: the solution nearest to a nearby `seed`, typically the previous tick's
    /// solution. Never wraps joints by 2π, so the result stays on the seed's branch and a
    /// commanded trajectory cannot jump a whole turn.
    ///
    /// A chain of a closed-form family, when the seed misses the target by more than
    /// [`NEWTON_NEAR`], takes the closed-form solution that follows the seed's branch if no
    /// joint moves more than [`TRACKING_JUMP`] from it (a larger jump means the seed's branch
    /// has no exact solution here, e.g. beyond a limit, and Newton's best effort is the
    /// answer); otherwise, and for every other chain, [`newton_tracking`](Self::newton_tracking).
    pub fn solve_tracking(
        &self,
        target: &Frame,
        seed: &[f64],
        config: &IkConfig,
    ) -> Result<IkResult, IkError> {
        self.solve_tracking_after(target, seed, config, &mut LastEvaluation::default())
    }

    /// [`solve_tracking`](Self::solve_tracking), reusing `last` (this chain's last pose
    /// evaluation) if the seed is the joints it evaluated, and leaving this solve's last one
    /// there: a control tick seeds each solve with the answer of the one before.
    pub fn solve_tracking_after(
        &self,
        target: &Frame,
        seed: &[f64],
        config: &IkConfig,
        last: &mut LastEvaluation,
    ) -> Result<IkResult, IkError> {
        self.track(target, (seed, None), config, Some(last), None)
    }

    /// [`solve_tracking`](Self::solve_tracking) for a caller that knows the pose at `seed`
    /// (`seed_pose`; a Cartesian line's previous point). It only chooses between Newton and
    /// the closed form, so an approximate pose does no harm; the seed's forward kinematics,
    /// a sixth of the closed form's cost on the Cortex-M7, is then spared unless Newton runs.
    /// `angles`: the seed's [`SeedAngles`] (those of the solve that answered it) and where to
    /// leave the answer's.
    pub fn solve_tracking_from(
        &self,
        target: &Frame,
        (seed, seed_pose): (&[f64], &Frame),
        config: &IkConfig,
        angles: (&SeedAngles, &mut SeedAngles),
    ) -> Result<IkResult, IkError> {
        self.track(target, (seed, Some(seed_pose)), config, None, Some(angles))
    }

    /// Tracking IK from `seed`, whose pose may be known, with the last evaluation if the
    /// caller keeps one (else a buffer of Newton's own, built only if Newton runs: zeroing
    /// its 560 bytes is a tenth of a closed-form solve on the Cortex-M7), and the seed's
    /// angles if the caller keeps them (then also the answer's).
    fn track(
        &self,
        target: &Frame,
        (seed, seed_pose): (&[f64], Option<&Frame>),
        config: &IkConfig,
        mut last: Option<&mut LastEvaluation>,
        angles: Option<(&SeedAngles, &mut SeedAngles)>,
    ) -> Result<IkResult, IkError> {
        // Without a caller that keeps them, the answer's angles are not copied out.
        let unknown = SeedAngles::default();
        let (seed_angles, mut answer) = match angles {
            Some((seed_angles, answer)) => (seed_angles, Some(answer)),
            None => (&unknown, None),
        };
        forget(answer.as_deref_mut());
        let mut start = [0.0; MAX_JOINTS];
        self.prepare(target, seed, &mut start)?;
        // m + rad, the angle read without a logarithm (it only chooses the method).
        let near = |pose: &Frame| Misses::of(pose, target).closer_than(NEWTON_NEAR);
        // Close to the target (the control tick's case, and a seed that already reaches it:
        // returned bit for bit) Newton converges in two or three steps, fewer instructions
        // than the closed form; farther out the closed form wins. The seed's pose, unless
        // known, is evaluated once: Newton's first step reuses it.
        let newton = match (self.closed_form(), seed_pose, last.as_deref_mut()) {
            (None, _, _) => true,
            (Some(_), Some(pose), _) => near(pose),
            (Some(_), None, Some(last)) => near(&last.at(self, &start)),
            (Some(_), None, None) => false,
        };
        if !newton {
            let within_jump = |q: &[f64]| {
                q.iter()
                    .zip(seed)
                    .all(|(a, b)| (a - b).abs() <= TRACKING_JUMP)
            };
            let mut found = IkSolution {
                q: Joints::zeros(self.dof()),
                iterations: 0,
                position_error: 0.0,
                orientation_error: 0.0,
            };
            let tolerance = config.tolerance;
            let seed = (&start, seed_angles);
            if self.follow(target, seed, tolerance, &mut found, answer.as_deref_mut())
                && within_jump(&found.q)
            {
                return Ok(IkResult::Converged(found));
            }
            forget(answer);
        }
        Ok(match last {
            Some(last) => self.newton_from(target, &start, config, last),
            None => self.newton_from(target, &start, config, &mut LastEvaluation::default()),
        })
    }

    /// Tracking IK by damped Newton steps alone from a nearby `seed`, typically the previous
    /// tick's solution. Never wraps joints by 2π, so the result stays on the seed's branch and
    /// a commanded trajectory cannot jump a whole turn.
    ///
    /// The limits only matter when the nearby solution violates them, so the first descent
    /// ignores them and its answer is checked; only if it breaks a limit (or does not converge)
    /// does a bounded descent from the same seed follow. An unbounded Newton path may pass
    /// outside a limit on its way to a solution inside; a bounded one can then end on the
    /// limit in a local minimum (seeds a few millimetres inside UR5's ±2π limits did).
    pub fn newton_tracking(
        &self,
        target: &Frame,
        seed: &[f64],
        config: &IkConfig,
    ) -> Result<IkResult, IkError> {
        let mut q = [0.0; MAX_JOINTS];
        self.prepare(target, seed, &mut q)?;
        Ok(self.newton_from(target, &q, config, &mut LastEvaluation::default()))
    }

    /// [`newton_tracking`](Self::newton_tracking) from a checked seed, whose pose and axes may
    /// have been evaluated already (`last`).
    fn newton_from(
        &self,
        target: &Frame,
        q: &[f64; MAX_JOINTS],
        config: &IkConfig,
        last: &mut LastEvaluation,
    ) -> IkResult {
        let (iterations, tolerance) = (config.tracking_iterations, config.tolerance);
        let no_hook = &mut || {};
        let free = self.descend(
            target,
            *q,
            iterations,
            tolerance,
            (Bounds::Free, &mut *last),
            no_hook,
        );
        let mut used = free.steps;
        if free.converged {
            if self.within_limits(&free.best.q) {
                return IkResult::Converged(free.best);
            }
            // Converged beyond a limit: near a stretched or folded singularity the nearby
            // branches mirror each other about the joint value there, so the solution
            // reflected about the limit seeds the bounded descent well.
            let mirrored = self.reflected_into_limits(&free.best.q);
            let retry = self.descend(
                target,
                mirrored,
                iterations,
                tolerance,
                (Bounds::Enforced, &mut *last),
                no_hook,
            );
            used += retry.steps;
            if retry.converged {
                let mut best = retry.best;
                best.iterations = used;
                return IkResult::Converged(best);
            }
        }
        let bounds = (Bounds::Enforced, last);
        let mut bounded = self.descend(target, *q, iterations, tolerance, bounds, no_hook);
        bounded.best.iterations += used;
        bounded.into_result()
    }

    /// Global IK. A chain of a closed-form family takes the exact solution nearest `seed` if
    /// there is one. Otherwise (and for every other chain) it descends from `seed`, then from
    /// deterministic random configurations drawn with `rng_seed`, until one converges within
    /// the limits or `config.global_iterations` iterations are spent. The same inputs always
    /// give the same answer.
    pub fn solve_global(
        &self,
        target: &Frame,
        seed: &[f64],
        config: &IkConfig,
        rng_seed: u64,
    ) -> Result<IkResult, IkError> {
        if self.closed_form().is_some()
            && let Some(found) = self.nearest_exact(target, seed, None)?
            && let Some(solution) = found.within(config.tolerance)
        {
            return Ok(IkResult::Converged(solution));
        }
        self.solve_global_counted(target, seed, config, rng_seed, &mut || {})
    }

    /// [`solve_global`](Self::solve_global), calling `on_step` once per Newton step taken, so a
    /// test can count the budget spent independently of the reported `iterations`.
    fn solve_global_counted(
        &self,
        target: &Frame,
        seed: &[f64],
        config: &IkConfig,
        rng_seed: u64,
        on_step: &mut impl FnMut(),
    ) -> Result<IkResult, IkError> {
        let mut start = [0.0; MAX_JOINTS];
        self.prepare(target, seed, &mut start)?;
        let mut q = start;
        let mut rng = SplitMix64::new(rng_seed);
        let mut budget = config.global_iterations;
        let mut best: Option<IkSolution> = None;
        let mut used = 0u32;
        let mut last = LastEvaluation::default();
        // Each attempt spends at least one iteration, so this bound is never the binding one.
        for _ in 0..config.global_iterations {
            let limit = budget.min(ATTEMPT_ITERATIONS);
            let descent = self.descend(
                target,
                q,
                limit,
                config.tolerance,
                (Bounds::Wrapping, &mut last),
                on_step,
            );
            used += descent.steps;
            // The steps actually taken (at most `limit`), not the index of the best pose: the
            // budget bounds the work. An attempt takes at least one step unless it converged.
            let spent = u16::try_from(descent.steps).unwrap_or(u16::MAX).max(1);
            budget = budget.saturating_sub(spent);
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
            self.descend(
                target,
                start,
                0,
                config.tolerance,
                (Bounds::Wrapping, &mut last),
                on_step,
            )
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
            *o = saturate(reflected, *lo, *hi);
        }
        out
    }

    /// Validates the inputs and writes the seed clamped into the limits to `q` (entries past
    /// the joint count zero). Written in place: returned inside the `Result`, the array sat
    /// unaligned and the Cortex-M7 copied it byte by byte, three times (≈ 900 instructions a
    /// tick in qemu-bench).
    pub(super) fn prepare(
        &self,
        target: &Frame,
        seed: &[f64],
        q: &mut [f64; MAX_JOINTS],
    ) -> Result<(), IkError> {
        if !math::is_finite(target) {
            return Err(IkError::NonFiniteTarget);
        }
        if seed.len() != self.dof() {
            return Err(IkError::WrongJointCount);
        }
        *q = [0.0; MAX_JOINTS];
        let (min, max) = self.limits();
        for ((v, s), (lo, hi)) in q.iter_mut().zip(seed).zip(min.iter().zip(max)) {
            if !s.is_finite() {
                return Err(IkError::NonFiniteSeed);
            }
            *v = saturate(*s, *lo, *hi);
        }
        Ok(())
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

    /// Damped Newton iterations from `q` (its pose and axes reused from `last` if evaluated
    /// there; every evaluation is left there); returns the best pose visited.
    fn descend(
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

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::math::{Rotation3, Vector3};

    fn ranger() -> (Chain, IkConfig) {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../robots/ranger-mk1.toml");
        let config = crate::config::load_file(path).unwrap();
        (Chain::new(&config), config.ik)
    }

    /// The budget bounds the Newton steps actually taken, counted by the solver's step hook
    /// rather than read back from the reported `iterations`.
    #[test]
    fn global_budget_bounds_the_steps_taken() {
        let (chain, ik) = ranger();
        for budget in [1, 29, 30, 31, 300] {
            let ik = IkConfig {
                global_iterations: budget,
                ..ik
            };
            for k in 0..20u32 {
                // 4 m out: beyond the ~1.5 m reach, so every attempt runs until it stalls or
                // exhausts its share and the whole budget is spent.
                let turn = Vector3::new(0.1 * f64::from(k), -0.3, 0.7);
                let target =
                    Frame::from_parts(Vector3::new(-0.5, 4.0, 0.7).into(), Rotation3::new(turn));
                let mut steps = 0u32;
                let result = chain
                    .solve_global_counted(
                        &target,
                        &chain.mid_range(),
                        &ik,
                        u64::from(k),
                        &mut || steps += 1,
                    )
                    .unwrap();
                assert!(!result.is_converged());
                assert_eq!(steps, u32::from(budget), "budget {budget}, seed {k}");
                assert_eq!(result.solution().iterations, steps);
            }
        }
    }

    /// A converged global solve reports the steps of every attempt, not just the last one's.
    #[test]
    fn global_iterations_count_every_attempt() {
        let (chain, ik) = ranger();
        let mut rng = crate::rng::SplitMix64::new(3);
        for k in 0..200 {
            let q = chain.random_joints(&mut rng);
            let target = chain.forward(&q).unwrap();
            let mut steps = 0u32;
            let result = chain
                .solve_global_counted(&target, &chain.mid_range(), &ik, k, &mut || steps += 1)
                .unwrap();
            assert_eq!(result.solution().iterations, steps);
            assert!(steps <= u32::from(ik.global_iterations));
        }
    }
}
