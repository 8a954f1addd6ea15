//! A chain only near its family (a calibrated robot file: fitted twists, lengths, offsets and
//! Hayati β). Each root of the ideal model is carried to the true chain ([`Chain::refine`]),
//! polished by Newton steps to full precision ([`Chain::polish`]), and near a singularity,
//! where two roots can carry to the same solution of the true chain and the chain can have
//! more solutions than the ideal model has roots, the solutions they miss are searched for
//! ([`Chain::complete`]).

use nalgebra::{Cholesky, Matrix6, Vector6};

use super::chain::{Axes, Chain};
use super::closed_form::{
    Branch, BranchSolution, CHECK, Candidate, Candidates, MAX_SOLUTIONS, Misses, Solutions,
    nearest_turn,
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
/// An error (m + rad) above which a polished solution is taken to full precision
/// ([`Chain::sharpen`]).
const SHARP_FROM: f64 = 1e-13;
/// Most searches ([`SEARCH_STEPS`] each) one solve spends on solutions the roots miss.
const SEARCHES: usize = 8;
/// Newton steps of the search for a solution other than the known ones.
const SEARCH_STEPS: usize = 40;
/// Damping floor of that search (the error-damped rule of the numeric solver).
const SEARCH_DAMPING: f64 = 1e-12;
/// The most a joint moves in one step of that search (rad or m).
const SEARCH_STEP: f64 = 0.3;
/// Below this ratio of `|det J|` to the product of its column lengths a solution counts as
/// near a singularity (about 1.6 % of random configurations of the shipped 6R arms).
const NEAR_SINGULAR: f64 = 2e-4;
/// How far (rad or m) beside a solution near a singularity a search for a second one starts.
const BESIDE: f64 = 0.05;
/// Inverse iterations that find the direction in which the Jacobian is nearest singular.
const KERNEL_ITERATIONS: usize = 4;
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
            let reached = self.pose_of(form, &current);
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
        let newton = *self.newton_tracking(target, q, &config).ok()?.solution();
        let mut q = newton.q;
        // Below this a solution is exact to ~1e-8 rad even near a singularity.
        if newton.position_error + newton.orientation_error > SHARP_FROM {
            self.sharpen(target, &mut q);
        }
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
        let mut repeated = [false; MAX_SOLUTIONS];
        for (solution, repeats) in carried.iter().zip(&mut repeated) {
            *repeats = listed.iter().any(|s| same(&s.q, &solution.q));
            if !*repeats {
                // Never full: no more solutions than were listed.
                let _ = listed.push(*solution);
            }
        }
        // Near a singularity the true chain can have more solutions than the ideal model has
        // roots (a third and fourth of a shoulder or wrist choice, 0.01–1 rad apart).
        let found = listed.clone();
        let repeats = carried.iter().zip(repeated).filter(|(_, r)| *r);
        let from = repeats
            .map(|(s, _)| s)
            .chain(found.iter().filter(|s| self.near_singular(&s.q)));
        let mut budget = SEARCHES;
        for solution in from {
            self.search(
                self.starts(candidates, solution),
                solution.branch,
                (target, reference),
                (&carried, listed),
                &mut budget,
            );
        }
    }

    /// The first solution for `target` found from `starts` other than every one `carried`
    /// and `listed`, added to the list on `branch` (if not full; each start tried spends one
    /// of `budget`).
    fn search(
        &self,
        starts: [Option<[f64; MAX_JOINTS]>; 3],
        branch: Branch,
        (target, reference): (&Frame, &[f64; MAX_JOINTS]),
        (carried, listed): (&Solutions, &mut Solutions),
        budget: &mut usize,
    ) {
        for start in starts.into_iter().flatten() {
            if listed.is_full() || *budget == 0 {
                return;
            }
            *budget -= 1;
            if let Some(q) = self.other_solution(start, target, reference, (carried, listed)) {
                let _ = listed.push(BranchSolution { q, branch });
                return;
            }
        }
    }

    /// The Jacobian at `q` of a six-joint chain (the measures of nearness to a singularity
    /// below need it square); `None` for other chains.
    fn six_joint_jacobian(&self, q: &Joints) -> Option<Jacobian> {
        if self.dof() != 6 {
            return None;
        }
        let (mut axes, mut jacobian) = (Axes::default(), Jacobian::zeros());
        let tool = self.tool_and_axes(q.as_array(), &mut axes);
        self.jacobian_into(&axes, &tool.translation.vector, &mut jacobian);
        Some(jacobian)
    }

    /// True if a six-joint chain's Jacobian at `q` is nearly singular: `|det J|` below
    /// [`NEAR_SINGULAR`] times the product of its column lengths (1 for orthogonal columns).
    /// False for other chains.
    fn near_singular(&self, q: &Joints) -> bool {
        let Some(jacobian) = self.six_joint_jacobian(q) else {
            return false;
        };
        let lengths: f64 = jacobian.column_iter().take(6).map(|c| c.norm()).product();
        // det(J Jᵀ) = det(J)², from its Cholesky factor; a Jacobian too singular for one is
        // near a singularity.
        Cholesky::new(jacobian * jacobian.transpose())
            .is_none_or(|c| c.determinant() < (NEAR_SINGULAR * lengths) * (NEAR_SINGULAR * lengths))
    }

    /// A solution of the true chain from `x` other than every one of `known`,
    /// on the turns nearest `reference` and within the limits. Newton steps whose length is
    /// scaled by `1/(1 − Σᵢ ∇mᵢ·d/mᵢ)`, `d` the Newton step and `mᵢ = 1/|q − sᵢ|² + 1` for
    /// each known solution `sᵢ`: Newton's method on the residual multiplied by every `mᵢ`,
    /// which has the same roots but the known ones, from which it is pushed away.
    fn other_solution(
        &self,
        mut x: [f64; MAX_JOINTS],
        target: &Frame,
        reference: &[f64; MAX_JOINTS],
        known: (&Solutions, &Solutions),
    ) -> Option<Joints> {
        let n = self.dof();
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
            let damping = 0.5 * e.norm_squared() + SEARCH_DAMPING;
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

    /// Starts of the search for a solution beside `solution` of `candidates`: the root it
    /// was carried from, then `solution` moved [`BESIDE`] either way along the direction in
    /// which the Jacobian there is nearest singular (where a second solution lies when two
    /// are close).
    fn starts(
        &self,
        candidates: &Candidates,
        solution: &BranchSolution,
    ) -> [Option<[f64; MAX_JOINTS]>; 3] {
        let root = candidates
            .iter()
            .find(|c| c.branch == solution.branch)
            .map(|c| root_of(c, self.dof()));
        let kernel = self.kernel_direction(&solution.q);
        let beside = |side: f64| {
            kernel.map(|v| {
                let mut x = [0.0; MAX_JOINTS];
                for ((x, q), v) in x.iter_mut().zip(solution.q.iter()).zip(v.iter()) {
                    *x = q + side * BESIDE * v;
                }
                x
            })
        };
        [root, beside(1.0), beside(-1.0)]
    }

    /// The unit joint direction along which the Jacobian at `q` is nearest singular: inverse
    /// iteration on `J Jᵀ` gives the task direction `u` of its smallest singular value `σ`,
    /// and `Jᵀ u = σ v`. `None` for a chain of other than six joints.
    fn kernel_direction(&self, q: &Joints) -> Option<JointVector> {
        let jacobian = self.six_joint_jacobian(q)?;
        let square = jacobian * jacobian.transpose() + Matrix6::from_diagonal_element(1e-15);
        let cholesky = Cholesky::new(square)?;
        let mut u = Vector6::repeat(1.0);
        for _ in 0..KERNEL_ITERATIONS {
            u = cholesky.solve(&u);
            u /= u.norm();
        }
        let v = jacobian.tr_mul(&u);
        let length = v.norm();
        (length > 0.0).then(|| v / length)
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

/// The joint values of `candidate`'s first `n` angles.
fn root_of(candidate: &Candidate, n: usize) -> [f64; MAX_JOINTS] {
    let mut x = [0.0; MAX_JOINTS];
    let values = candidate.angles.iter().zip(&candidate.values);
    for (x, (angle, value)) in x.iter_mut().zip(values).take(n) {
        *x = if value.is_nan() {
            angle.value()
        } else {
            *value
        };
    }
    x
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
