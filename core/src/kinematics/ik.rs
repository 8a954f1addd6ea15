//! Inverse position kinematics: the answer types, and tracking IK (the solution nearest a
//! nearby seed, the control tick's case) by the closed form or by damped Newton steps
//! ([`descent`](super::descent)). Global IK is in [`global`](super::global).

use super::chain::Chain;
use super::closed_form::{Misses, SeedAngles};
use super::descent::Bounds;
use super::evaluation::LastEvaluation;
use crate::MAX_JOINTS;
use crate::config::IkConfig;
use crate::math::Joints;
use crate::math::{self, Frame};
use crate::saturate::saturate;

/// The most a joint may move from the seed in a closed-form tracking solution (rad): beyond,
/// the seed's branch has no solution within the limits here.
pub const TRACKING_JUMP: f64 = 0.5;
/// Below this seed error (m + rad) tracking IK takes Newton steps even on a chain with a
/// closed form: from 3 mm they converge in two or three (about 9,500–14,000 Cortex-M7
/// instructions). Chosen when the closed form took about 13,500; it now takes about 6,300
/// (qemu-bench), but the control tick's rule is kept as it was.
const NEWTON_NEAR: f64 = 3e-3;

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
        // Every entry written once (zeroing first was a `memset` call, about 40 instructions
        // on the Cortex-M7): the seed's clamped, zero past it.
        let (min, max) = self.limits();
        for (i, (v, (lo, hi))) in q.iter_mut().zip(min.iter().zip(max)).enumerate() {
            *v = match seed.get(i) {
                Some(s) if !s.is_finite() => return Err(IkError::NonFiniteSeed),
                Some(s) => saturate(*s, *lo, *hi),
                None => 0.0,
            };
        }
        Ok(())
    }
}
