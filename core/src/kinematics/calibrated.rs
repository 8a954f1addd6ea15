//! A chain only near its family (a calibrated robot file: fitted twists, lengths, offsets and
//! Hayati β). Each root of the ideal model is carried to the true chain ([`Chain::refine`]),
//! polished by Newton steps to full precision ([`Chain::polish`]), and near a singularity,
//! where two roots can carry to the same solution of the true chain, the solutions they miss
//! are searched for ([`Chain::complete`]).

use super::chain::{Axes, Chain};
use super::closed_form::{
    BranchSolution, CHECK, Candidate, Candidates, Misses, Solutions, nearest_turn,
};
use super::family::ClosedForm;
use super::jacobian::{Jacobian, JointVector, damped_least_squares};
use crate::MAX_JOINTS;
use crate::config::IkConfig;
use crate::math::{self, Frame, Joints};

/// Newton steps that polish a solution of the ideal model on a calibrated chain.
const POLISH_ITERATIONS: u16 = 20;
/// Most re-solves of the ideal model that carry a root to a calibrated chain ([`Chain::refine`]).
const REFINE_STEPS: usize = 4;
/// A miss (m, rad) below which a carried root is left to Newton's polish.
const REFINED: f64 = 1e-7;
/// Newton steps of the search for a solution other than the known ones.
const SEARCH_STEPS: usize = 40;
/// The most a joint moves in one step of that search (rad or m).
const SEARCH_STEP: f64 = 0.3;
/// Below this ratio of `|det J|` to the product of its column lengths a solution counts as
/// near a singularity (about 1.6 % of random configurations of the shipped 6R arms).
const NEAR_SINGULAR: f64 = 2e-4;
/// Joint distance (∞-norm, whole turns ignored) within which two solutions are the same.
const SAME: f64 = 1e-7;

impl Chain {
    /// A chain only near its family: `candidate`, a root of the ideal model, carried towards
    /// the true chain's root on the same branch. With `D(q)` the true chain's pose relative to
    /// the ideal model's at `q` (slowly varying: the deviation is small), the true chain
    /// reaches `target` where the ideal model reaches `target · D(q)⁻¹`; so the ideal model is
    /// solved again for that corrected target, following the previous root at every choice
    /// (away from singularities a miss of 1e-3 falls below 1e-7 within the four passes, where
    /// Newton takes over). Unlike Newton steps on the true chain,
    /// this cannot slide to another branch near a singularity, where the ideal model's wrist
    /// angles can be ~0.1 rad off the true ones.
    pub(super) fn refine(
        &self,
        form: &ClosedForm,
        candidate: &Candidate,
        target: &Frame,
    ) -> Candidate {
        let mut current = *candidate;
        let mut ideal = *target;
        for _ in 0..REFINE_STEPS {
            let reached = self.pose_by_trig(&current.sin_cos());
            if Misses::of(&reached, target).largest() <= REFINED * REFINED {
                break;
            }
            ideal = target * reached.inverse() * ideal;
            let mut free = [0.0; MAX_JOINTS];
            for (f, a) in free.iter_mut().zip(&current.angles) {
                *f = a.value();
            }
            let mut next = Candidates::new();
            self.candidates_of(form, &ideal, (&free, None), true, &mut next);
            let Some(found) = next.first() else {
                break;
            };
            current = Candidate {
                branch: candidate.branch,
                ..*found
            };
        }
        current
    }

    /// Newton steps on the true chain from a solution of its ideal model (or from a root known
    /// only to √ε); the best pose reached.
    pub(super) fn polish(&self, target: &Frame, q: &Joints) -> Option<Joints> {
        let config = IkConfig {
            tolerance: 0.1 * CHECK,
            tracking_iterations: POLISH_ITERATIONS,
            ..IkConfig::default()
        };
        // Aiming below CHECK, Newton may stall on rounding just above its tolerance: its best
        // pose goes to the caller's check either way.
        let mut q = self.newton_tracking(target, q, &config).ok()?.solution().q;
        self.sharpen(target, &mut q);
        Some(q)
    }

    /// The solutions of a calibrated chain's `listed`, with every one that repeats an earlier
    /// one replaced, if it can be, by another solution near the ideal model's root it came
    /// from. Near a singularity the two roots of a choice lie close together and both can
    /// carry to the same solution of the true chain, while its second solution nearby is not
    /// listed.
    pub(super) fn complete(
        &self,
        candidates: &Candidates,
        target: &Frame,
        reference: &[f64; MAX_JOINTS],
        listed: &mut Solutions,
    ) {
        let carried = core::mem::take(listed);
        for solution in &carried {
            if !listed.iter().any(|s| same(&s.q, &solution.q)) {
                // Never full: no more solutions than were listed.
                let _ = listed.push(*solution);
                continue;
            }
            let branch = solution.branch;
            let Some(candidate) = candidates.iter().find(|c| c.branch == branch) else {
                continue;
            };
            if let Some(q) = self.other_solution(candidate, target, reference, (&carried, listed)) {
                let _ = listed.push(BranchSolution { q, branch });
            }
        }
        // A root that carried to no solution (or to one beyond a limit) may lie near one all
        // the same.
        for candidate in candidates {
            if !listed.is_full()
                && listed.iter().all(|s| s.branch != candidate.branch)
                && let Some(q) =
                    self.other_solution(candidate, target, reference, (&carried, listed))
            {
                let branch = candidate.branch;
                let _ = listed.push(BranchSolution { q, branch });
            }
        }
        // Near a singularity the true chain can have more solutions than the ideal model has
        // roots (a third and fourth of a shoulder or wrist choice, 0.01–1 rad apart).
        let found = listed.clone();
        for solution in found.iter().filter(|s| self.near_singular(&s.q)) {
            if !listed.is_full()
                && let Some(candidate) = candidates.iter().find(|c| c.branch == solution.branch)
                && let Some(q) =
                    self.other_solution(candidate, target, reference, (&carried, listed))
            {
                let branch = candidate.branch;
                let _ = listed.push(BranchSolution { q, branch });
            }
        }
    }

    /// True if a six-joint chain's Jacobian at `q` is nearly singular: `|det J|` below
    /// [`NEAR_SINGULAR`] times the product of its column lengths (1 for orthogonal columns).
    /// False for other chains.
    fn near_singular(&self, q: &Joints) -> bool {
        if self.dof() != 6 {
            return false;
        }
        let mut x = [0.0; MAX_JOINTS];
        for (x, v) in x.iter_mut().zip(q.iter()) {
            *x = *v;
        }
        let (mut axes, mut jacobian) = (Axes::default(), Jacobian::zeros());
        let tool = self.tool_and_axes(&x, &mut axes);
        self.jacobian_into(&axes, &tool.translation.vector, &mut jacobian);
        let square = jacobian.fixed_columns::<6>(0).into_owned();
        let lengths: f64 = square.column_iter().map(|c| c.norm()).product();
        square.determinant().abs() < NEAR_SINGULAR * lengths
    }

    /// A solution of the true chain from `candidate`'s root other than every one of `known`,
    /// on the turns nearest `reference` and within the limits. Newton steps whose length is
    /// scaled by `1/(1 − Σᵢ ∇mᵢ·d/mᵢ)`, `d` the Newton step and `mᵢ = 1/|q − sᵢ|² + 1` for
    /// each known solution `sᵢ`: Newton's method on the residual multiplied by every `mᵢ`,
    /// which has the same roots but the known ones, from which it is pushed away.
    fn other_solution(
        &self,
        candidate: &Candidate,
        target: &Frame,
        reference: &[f64; MAX_JOINTS],
        known: (&Solutions, &Solutions),
    ) -> Option<Joints> {
        let n = self.dof();
        let mut x = [0.0; MAX_JOINTS];
        let values = candidate.angles.iter().zip(&candidate.values);
        for (x, (angle, value)) in x.iter_mut().zip(values).take(n) {
            *x = if value.is_nan() {
                angle.value()
            } else {
                *value
            };
        }
        let known = || known.0.iter().chain(known.1.iter());
        let (mut axes, mut jacobian) = (Axes::default(), Jacobian::zeros());
        let mut found = false;
        for _ in 0..SEARCH_STEPS {
            let tool = self.tool_and_axes(&x, &mut axes);
            let e = math::diff(&tool, target);
            if e.norm_squared() < 0.01 * CHECK * CHECK {
                found = !known().any(|s| same(&s.q, &x));
                break;
            }
            self.jacobian_into(&axes, &tool.translation.vector, &mut jacobian);
            let damping = 0.5 * e.norm_squared() + 1e-12;
            let none = [false; MAX_JOINTS];
            let d = damped_least_squares(&jacobian, n, &e, damping, &none)?;
            let mut slope = 0.0;
            for s in known() {
                let r = self.turn_difference(&x, &s.q);
                let rho = r.norm_squared();
                slope -= 2.0 * r.dot(&d) / (rho * (1.0 + rho));
            }
            let mut scale = 1.0 / (1.0 - slope);
            if !scale.is_finite() {
                scale = 1.0;
            }
            let longest = scale.abs() * d.amax();
            if longest > SEARCH_STEP {
                scale *= SEARCH_STEP / longest;
            }
            for (x, d) in x.iter_mut().zip(d.iter()) {
                *x += scale * d;
            }
        }
        if !found {
            return None;
        }
        let (min, max) = self.limits();
        let mut q = Joints::zeros(n);
        let joints = q.iter_mut().zip(&x).zip(reference).zip(min.iter().zip(max));
        for (i, (((v, x), r), (lo, hi))) in joints.enumerate() {
            *v = if self.is_prismatic(i) {
                (lo <= x && x <= hi).then_some(*x)?
            } else {
                nearest_turn(*x, *r, *lo, *hi)?
            };
        }
        self.sharpen(target, &mut q);
        let fresh = !known().any(|s| same(&s.q, &q));
        (fresh && Misses::of(&self.pose(&q), target).largest() <= CHECK * CHECK).then_some(q)
    }

    /// `a − b` joint by joint, revolute joints by less than half a turn.
    fn turn_difference(&self, a: &[f64; MAX_JOINTS], b: &Joints) -> JointVector {
        let mut r = JointVector::zeros();
        for (i, (r, (a, b))) in r.iter_mut().zip(a.iter().zip(b.iter())).enumerate() {
            *r = if self.is_prismatic(i) {
                a - b
            } else {
                wrapped(a - b)
            };
        }
        r
    }
}

/// `d` less the whole turns nearest it.
fn wrapped(d: f64) -> f64 {
    const TAU: f64 = core::f64::consts::TAU;
    d - TAU * libm::round(d / TAU)
}

/// Equal joint by joint within [`SAME`], whole turns ignored.
fn same(a: &[f64], b: &[f64]) -> bool {
    a.iter().zip(b).all(|(a, b)| wrapped(a - b).abs() <= SAME)
}
