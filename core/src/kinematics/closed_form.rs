//! Every inverse-kinematics solution in closed form, for chains of a known [`Family`].
//!
//! A family solver ([`spherical_wrist`](super::spherical_wrist),
//! [`three_parallel`](super::three_parallel)) lists candidate solutions as angles with their
//! [`Branch`]. Each candidate is then taken to the 2π turn of every revolute joint that lies
//! within the limits nearest to a reference configuration (the present joints), polished by
//! Newton steps on the true chain if the chain only approximately belongs to its family, and
//! kept only if forward kinematics reproduces the target within [`CHECK`]. So every solution
//! returned is exact and admissible; a pose with none returns an empty list.

use heapless::Vec;
use nalgebra::{Matrix3, Vector3};

use super::chain::Chain;
use super::family::{ClosedForm, Family, FamilyFit};
use super::ik::{IkError, IkSolution};
use super::subproblems::{Angle, sp4};
use super::{prismatic_base, spherical_shoulder, spherical_wrist, three_parallel};
use crate::MAX_JOINTS;
use crate::math::Frame;
use crate::math::Joints;
use crate::saturate::saturate;

/// Most solutions of a closed-form solve (2 shoulders · 2 elbows · 2 wrists).
pub const MAX_SOLUTIONS: usize = 8;
/// Position (m) and orientation (rad) error up to which a solution counts as reproducing the
/// target.
pub const CHECK: f64 = 1e-9;
/// A candidate this close to the target (m, rad) but not within [`CHECK`] is polished.
const POLISH_FROM: f64 = 1e-5;

/// A configuration branch of a closed-form family: which root each of the three two-way
/// choices took. Bit 0 is the shoulder (the second root of θ1; of θ1, θ2 for a spherical
/// shoulder), bit 1 the elbow (of θ3; of θ4 for a spherical shoulder), bit 2 the wrist (of θ4,
/// θ5 for a spherical wrist; of θ5 for three parallel axes; of the wrist's first two solved
/// joints for a spherical shoulder). A prismatic base sets bit 0 for the second root of θ3
/// and θ4 + θ5 (the base turned about half a turn) and bit 1 for that of θ4, never bit 2.
/// Flipping a bit gives the mirrored configuration: shoulder left/right, elbow up/down, wrist
/// flipped.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Branch(u8);

impl Branch {
    /// Shoulder bit.
    pub const SHOULDER: u8 = 1;
    /// Elbow bit.
    pub const ELBOW: u8 = 2;
    /// Wrist bit.
    pub const WRIST: u8 = 4;

    /// The branch with these bits; `None` above 7.
    pub const fn from_bits(bits: u8) -> Option<Self> {
        if bits < 8 { Some(Self(bits)) } else { None }
    }

    /// Its bits.
    pub const fn bits(self) -> u8 {
        self.0
    }

    /// The branch of the roots taken (each 0 or 1).
    pub(super) fn from_roots(shoulder: u8, elbow: u8, wrist: u8) -> Self {
        Self((shoulder & 1) | (elbow & 1) << 1 | (wrist & 1) << 2)
    }

    /// This branch with the wrist root `wrist`.
    pub(super) fn with_wrist(self, wrist: u8) -> Self {
        Self(self.0 & !Self::WRIST | (wrist & 1) << 2)
    }
}

/// One exact solution and its branch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BranchSolution {
    /// Joint values within the limits.
    pub q: Joints,
    /// The branch it lies on.
    pub branch: Branch,
}

/// Every solution of a closed-form solve.
pub type Solutions = Vec<BranchSolution, MAX_SOLUTIONS>;

/// A candidate of a family solver: angles of the joints (zero past the last) and the branch.
#[derive(Clone, Copy, Debug)]
pub(super) struct Candidate {
    pub angles: [Angle; MAX_JOINTS],
    /// The values of the angles a solver already took (`atan2` once for a root that several
    /// candidates share); NaN where not.
    pub values: [f64; MAX_JOINTS],
    pub branch: Branch,
    /// Every value taken and passed by a [`Gate`] (on the turn nearest the reference, within
    /// the limits): the values are the solution's joints as they are, and the angles alone
    /// give its pose. Only an exact family's gate is closed, and a prismatic base's solver
    /// takes none (its pose needs the slides), so this is never set for either.
    pub admitted: bool,
}

impl Candidate {
    /// A candidate of a six-joint arm's `angles` on `branch`, with the `known` values (NaN:
    /// not taken yet), `admitted` if a [`Gate`] passed all of them.
    pub fn new(angles: [Angle; 6], known: [f64; 6], branch: Branch, admitted: bool) -> Self {
        let zero = Angle { cos: 1.0, sin: 0.0 };
        let mut all = Self::of_joints([zero; MAX_JOINTS], [0.0; MAX_JOINTS], branch);
        let slots = all.angles.iter_mut().zip(all.values.iter_mut());
        for ((a, v), (x, k)) in slots.zip(angles.into_iter().zip(known)) {
            (*a, *v) = (x, k);
        }
        all.admitted = admitted;
        all
    }

    /// A candidate of every joint's `angles` (and `known` values, NaN where not taken).
    pub fn of_joints(
        angles: [Angle; MAX_JOINTS],
        known: [f64; MAX_JOINTS],
        branch: Branch,
    ) -> Self {
        Self {
            angles,
            values: known,
            branch,
            admitted: false,
        }
    }
}

/// The joint limits as a family solver applies them: to each joint value as soon as it has
/// it, on the turn nearest the reference, so that a branch outside them is dropped before its
/// remaining joints are solved and its candidates need no limit test afterwards. Open (every
/// value passes, as it is) for the ideal model of a calibrated arm, whose roots lie near the
/// true ones only: they are tested after their refinement.
#[derive(Clone, Copy)]
pub(super) struct Gate<'a>(Option<GateLimits<'a>>);

/// A closed [`Gate`]'s reference and limits.
type GateLimits<'a> = (
    &'a [f64; MAX_JOINTS],
    &'a [f64; MAX_JOINTS],
    &'a [f64; MAX_JOINTS],
);

impl Gate<'_> {
    /// Joint `i`'s `value` on the turn nearest the reference within the limits; `None` if no
    /// turn is within them. An open gate passes every value as it is.
    pub fn admit(&self, i: usize, value: f64) -> Option<f64> {
        let Some((reference, min, max)) = self.0 else {
            return Some(value);
        };
        match (reference.get(i), min.get(i), max.get(i)) {
            (Some(r), Some(lo), Some(hi)) => nearest_turn(value, *r, *lo, *hi),
            _ => None,
        }
    }

    /// True if it tests the limits (the values it passes are then the solution's).
    pub fn is_closed(&self) -> bool {
        self.0.is_some()
    }
}

/// The angles of a tracking seed's joints, where the caller has them: each spares a `sincos`
/// at a two-way choice.
pub(super) type Known<'a> = Option<&'a [Angle; MAX_JOINTS]>;

/// Joint `i`'s angle in `known`, if any.
pub(super) fn known_angle(known: Known<'_>, i: usize) -> Option<&Angle> {
    known.and_then(|angles| angles.get(i))
}

/// The joint angles (sines and cosines) of a closed-form tracking solve's answer, kept to seed
/// the next solve from that answer: it then compares its roots with them instead of taking the
/// `sincos` of four seed joints (about 400 Cortex-M7 instructions). Empty when the answer came
/// from Newton steps or from an approximate (calibrated) family's refined root.
#[derive(Clone, Copy, Debug, Default)]
pub struct SeedAngles(Option<[Angle; MAX_JOINTS]>);

/// Where both families start: the target's rotation relative to the tool's at q = 0
/// (`R1 ⋯ R6`), the target's place for the form's centre (which moves with the joints before
/// the last two or three only) relative to axis 1's point, and the roots of θ1 that keep its
/// component along axis 2 (subproblem 4: rotations about axis 2 and the axes parallel to it
/// keep it).
pub(super) struct Shoulder {
    pub tool: Matrix3<f64>,
    pub v: Vector3<f64>,
    pub roots: ([(Angle, u8); 2], usize),
}

impl Shoulder {
    /// The start of `form`'s solve for `target` (`nearest`: only the root nearest `free`, whose
    /// angle may be `known`).
    pub fn of(
        form: &ClosedForm,
        target: &Frame,
        (free, known): (f64, Option<&Angle>),
        nearest: bool,
    ) -> Self {
        let s = &form.screws;
        let [h1, h2, _, _, _, _, _, _] = &s.axis;
        let o1 = &s.point[0];
        let c = &form.centre;
        let tool = target.rotation.matrix() * s.tool_rotation.transpose();
        let v = target.translation.vector - tool * (s.tool_position - c) - o1;
        let roots = sp4(&v, h1, h2, h2.dot(&(c - o1)), form.slack()).list(free, known, nearest);
        Self { tool, v, roots }
    }
}

/// A checked solution with its errors, squared (the square roots are taken only for the
/// one answer that reports them: on the Cortex-M7 each is a software `sqrt`).
#[derive(Clone, Copy, Debug)]
pub(super) struct Exact {
    pub solution: BranchSolution,
    errors: Misses,
}

impl Exact {
    /// As an [`IkSolution`] (no Newton steps), if both errors are below `tolerance`.
    pub fn within(&self, tolerance: f64) -> Option<IkSolution> {
        let mut solution = IkSolution {
            q: self.solution.q,
            iterations: 0,
            position_error: 0.0,
            orientation_error: 0.0,
        };
        self.errors
            .report_within(tolerance, &mut solution)
            .then_some(solution)
    }
}

/// The candidates of one solve.
pub(super) type Candidates = Vec<Candidate, MAX_SOLUTIONS>;

impl Chain {
    /// The closed-form family this chain belongs to, detected when it was built.
    pub fn family(&self) -> FamilyFit {
        self.closed_form().map_or(
            FamilyFit {
                family: Family::Numeric,
                deviation: f64::INFINITY,
            },
            |form| form.fit,
        )
    }

    /// Every solution for `target` within the joint limits, each on its own branch, each
    /// revolute joint on the 2π turn nearest to `reference` (the present joints; also the
    /// value kept by a joint a singularity leaves free). Refused with
    /// [`IkError::NoClosedForm`] for a [`Family::Numeric`] chain.
    pub fn solve_all(&self, target: &Frame, reference: &[f64]) -> Result<Solutions, IkError> {
        let mut all = Solutions::new();
        self.solve_all_into(target, reference, &mut all)
            .map(|()| all)
    }

    /// [`solve_all`](Self::solve_all) into the caller's list (emptied first): a returned list
    /// is copied on the Cortex-M7 (650 bytes, about 330 instructions), and so is each solution
    /// pushed by value; here every solution is written in its slot.
    pub fn solve_all_into(
        &self,
        target: &Frame,
        reference: &[f64],
        solutions: &mut Solutions,
    ) -> Result<(), IkError> {
        solutions.clear();
        let (mut checked, mut candidates) = ([0.0; MAX_JOINTS], Candidates::new());
        let form = self.candidates(target, reference, false, (&mut checked, &mut candidates))?;
        let exact = form.fit.is_exact();
        let flange = target.rotation.matrix() * self.tool_rotation().transpose();
        for candidate in &candidates {
            let slot = BranchSolution {
                q: Joints::from_array(candidate.values, self.dof()),
                branch: candidate.branch,
            };
            // Never full: one solution per candidate, at most MAX_SOLUTIONS candidates.
            let (Ok(()), Some(solution)) = (solutions.push(slot), solutions.last_mut()) else {
                break;
            };
            // The common case apart: a candidate that a gate admitted (an exact revolute
            // family's) needs only its FK check (through `finish`, about 110 more instructions
            // on the M7).
            let aim = (&flange, &target.translation.vector);
            let reached = candidate.admitted
                && Misses::of_flange(self.misses_by_trig(&candidate.angles, aim)).largest()
                    <= CHECK * CHECK;
            let kept = reached
                || self
                    .finish(form, candidate, target, (&checked, &mut solution.q))
                    .is_some();
            if !kept {
                solutions.truncate(solutions.len().saturating_sub(1));
            }
        }
        if !exact {
            self.complete(&candidates, target, &checked, solutions);
        }
        Ok(())
    }

    /// The solution nearest to `reference` (on `branch` if given): the candidates are tried
    /// from the nearest, so usually only one is checked. `None` if there is none.
    pub fn solve_nearest(
        &self,
        target: &Frame,
        reference: &[f64],
        branch: Option<Branch>,
    ) -> Result<Option<BranchSolution>, IkError> {
        Ok(self
            .nearest_exact(target, reference, branch)?
            .map(|e| e.solution))
    }

    /// [`solve_nearest`](Self::solve_nearest) with the solution's errors. A redundant chain
    /// whose parameters have no solution at the reference's values takes the first values of a
    /// sweep across their ranges that has one.
    pub(super) fn nearest_exact(
        &self,
        target: &Frame,
        reference: &[f64],
        branch: Option<Branch>,
    ) -> Result<Option<Exact>, IkError> {
        let mut clamped = [0.0; MAX_JOINTS];
        self.prepare(target, reference, &mut clamped)?;
        let reference = clamped;
        let found = self.nearest_for(target, &reference, branch)?;
        let redundant = self
            .closed_form()
            .filter(|form| form.fit.family == Family::SphericalShoulder);
        let Some(form) = redundant.filter(|_| found.is_none()) else {
            return Ok(found);
        };
        if !spherical_shoulder::elbow_reaches(form, target) {
            return Ok(None);
        }
        // The first reference of the sweep is the one just tried.
        for k in 1..spherical_shoulder::SWEEP_TRIES {
            let Some(values) = spherical_shoulder::swept(self, &reference, k) else {
                break;
            };
            if let Some(found) = self.nearest_for(target, &values, branch)? {
                return Ok(Some(found));
            }
        }
        Ok(None)
    }

    /// The nearest solution for `reference`'s redundancy parameters.
    pub(super) fn nearest_for(
        &self,
        target: &Frame,
        reference: &[f64; MAX_JOINTS],
        branch: Option<Branch>,
    ) -> Result<Option<Exact>, IkError> {
        let dof = reference.get(..self.dof()).unwrap_or(&[]);
        let (mut checked, mut candidates) = ([0.0; MAX_JOINTS], Candidates::new());
        let form = self.candidates(target, dof, false, (&mut checked, &mut candidates))?;
        let mut near = [Angle::of(0.0); MAX_JOINTS];
        for (a, r) in near.iter_mut().zip(&checked) {
            *a = Angle::of(*r);
        }
        // 1 − cos of each joint's distance to the reference, summed: no atan2 per candidate
        // (a slide's angle is zero for every candidate: its distance is added apart).
        let slides = form.fit.family == Family::PrismaticBase;
        let mut distance = [f64::INFINITY; MAX_SOLUTIONS];
        for (d, c) in distance.iter_mut().zip(&candidates) {
            if branch.is_none_or(|b| b == c.branch) {
                *d = c
                    .angles
                    .iter()
                    .zip(&near)
                    .map(|(a, r)| 1.0 - a.closeness(r))
                    .sum();
                if slides {
                    *d += prismatic_base::slide_distance(&c.values, &checked);
                }
            }
        }
        // Nearest first (a selection, not a sort: a sort's code would cost the firmware
        // kilobytes for eight entries).
        for _ in 0..MAX_SOLUTIONS {
            let Some((k, _)) = distance
                .iter()
                .enumerate()
                .filter(|(_, d)| d.is_finite())
                .min_by(|(_, a), (_, b)| a.total_cmp(b))
            else {
                break;
            };
            if let Some(d) = distance.get_mut(k) {
                *d = f64::INFINITY;
            }
            let mut q = Joints::zeros(self.dof());
            if let Some(candidate) = candidates.get(k)
                && let Some(errors) = self.finish(form, candidate, target, (&checked, &mut q))
            {
                let branch = candidate.branch;
                let solution = BranchSolution { q, branch };
                return Ok(Some(Exact { solution, errors }));
            }
        }
        Ok(None)
    }

    /// The solution that follows the branch of a nearby `seed` (the tracking case): at each
    /// two-way choice the root nearest the seed, so one candidate is built and checked.
    /// Written to `solution` (whose joint count must be the chain's) if it reaches `target`
    /// within `tolerance`: returned by value, it was copied three times on the Cortex-M7.
    /// `seed` is one that [`prepare`](Self::prepare) checked for `target`; `seed_angles`, its
    /// angles if known. The answer's angles are written to `answer`, if given (left as they
    /// are if unknown).
    pub(super) fn follow(
        &self,
        target: &Frame,
        (seed, seed_angles): (&[f64; MAX_JOINTS], &SeedAngles),
        tolerance: f64,
        solution: &mut IkSolution,
        answer: Option<&mut SeedAngles>,
    ) -> bool {
        let mut candidates = Candidates::new();
        let Some(form) = self.closed_form() else {
            return false;
        };
        let known = seed_angles.0.as_ref();
        self.candidates_of(form, target, (seed, known), true, &mut candidates);
        candidates.first().is_some_and(|candidate| {
            let found = self
                .finish(form, candidate, target, (seed, &mut solution.q))
                .is_some_and(|errors| errors.report_within(tolerance, solution));
            // A refined root's angles are not the candidate's; the redundant family's solver
            // takes none (and copying them is not free).
            if found
                && form.fit.is_exact()
                && form.fit.family != Family::SphericalShoulder
                && let Some(answer) = answer
            {
                answer.0 = Some(candidate.angles);
            }
            found
        })
    }

    /// The branch of configuration `q`: the branch of the solution at `q`'s own pose that
    /// lies at `q`. `None` for a numeric chain or at a configuration no branch reproduces
    /// (within 1e-6 per joint).
    pub fn branch_of(&self, q: &[f64]) -> Option<Branch> {
        let pose = self.forward(q).ok()?;
        let found = self.solve_nearest(&pose, q, None).ok()??;
        let same = found.q.iter().zip(q).all(|(a, b)| (a - b).abs() <= 1e-6);
        same.then_some(found.branch)
    }

    /// The family; the checked reference is written to `checked` and the family solver's
    /// candidates (with `nearest`, only the one nearest `reference` at every choice) to `out`,
    /// both owned by the caller: returned by value, they were copied several times per solve
    /// (the candidate list is 1.2 KB).
    fn candidates(
        &self,
        target: &Frame,
        reference: &[f64],
        nearest: bool,
        (checked, out): (&mut [f64; MAX_JOINTS], &mut Candidates),
    ) -> Result<&ClosedForm, IkError> {
        let form = self.closed_form().ok_or(IkError::NoClosedForm)?;
        self.prepare(target, reference, checked)?;
        self.candidates_of(form, target, (checked, None), nearest, out);
        Ok(form)
    }

    /// The candidates of `form` for a checked `reference` (whose angles may be known), written
    /// to `out`.
    pub(super) fn candidates_of(
        &self,
        form: &ClosedForm,
        target: &Frame,
        (reference, known): (&[f64; MAX_JOINTS], Known<'_>),
        nearest: bool,
        out: &mut Candidates,
    ) {
        let (min, max) = self.limits();
        let gate = || Gate(form.fit.is_exact().then_some((reference, min, max)));
        match form.fit.family {
            Family::SphericalWrist => {
                spherical_wrist::solve(form, target, (reference, known), nearest, gate(), out);
            }
            Family::ThreeParallel => {
                three_parallel::solve(form, target, (reference, known), nearest, gate(), out);
            }
            Family::SphericalShoulder => {
                spherical_shoulder::solve(form, self.dof(), target, reference, nearest, out);
            }
            Family::PrismaticBase => {
                prismatic_base::solve(form, target, (reference, known), nearest, out);
            }
            Family::Numeric => {}
        }
    }

    /// A candidate on the turns nearest `reference`, polished if the family fit is
    /// approximate, written to `q` (of the chain's joint count); its errors if it is within
    /// the limits and reproduces `target`.
    fn finish(
        &self,
        form: &ClosedForm,
        candidate: &Candidate,
        target: &Frame,
        (reference, q): (&[f64; MAX_JOINTS], &mut Joints),
    ) -> Option<Misses> {
        if form.fit.is_exact() {
            return self.verify(form, candidate, target, (reference, q));
        }
        // The carried root; failing that, Newton steps from the ideal model's own.
        let refined = self.refine(form, candidate, target);
        self.verify(form, &refined, target, (reference, &mut *q))
            .or_else(|| self.verify(form, candidate, target, (reference, q)))
    }

    /// [`finish`](Self::finish) of a candidate as it is.
    fn verify(
        &self,
        form: &ClosedForm,
        candidate: &Candidate,
        target: &Frame,
        (reference, q): (&[f64; MAX_JOINTS], &mut Joints),
    ) -> Option<Misses> {
        let (min, max) = self.limits();
        // A gate's values are the joints already; any others are turned and tested here.
        let untested = if candidate.admitted {
            *q = Joints::from_array(candidate.values, q.len());
            0
        } else {
            MAX_JOINTS
        };
        let angles = candidate.angles.iter().zip(&candidate.values);
        let joints = q.iter_mut().zip(angles).zip(reference);
        // An ideal model's root may lie a little beyond a limit the true chain's is within:
        // widened limits, then Newton from the nearest point within them.
        let widen = if form.fit.is_exact() {
            0.0
        } else {
            form.slack()
        };
        for (((v, (angle, known)), r), (lo, hi)) in joints.zip(min.iter().zip(max)).take(untested) {
            let value = if known.is_nan() {
                angle.value()
            } else {
                *known
            };
            let turned = nearest_turn(value, *r, lo - widen, hi + widen)?;
            *v = saturate(turned, *lo, *hi);
        }
        // A slide takes no turns: its own value, if within its limits.
        if form.fit.family == Family::PrismaticBase
            && !prismatic_base::place_slides(&candidate.values, q, (min, max), widen)
        {
            return None;
        }
        if !form.fit.is_exact() {
            *q = self.polish(target, q)?;
        }
        let reached = if form.fit.is_exact() {
            self.pose_of(form, candidate)
        } else {
            self.pose(q)
        };
        let mut errors = Misses::of(&reached, target);
        if errors.largest() > CHECK * CHECK {
            // At a tangency (elbow stretched, wrist aligned) a root is only known to √ε
            // ≈ 1.5e-8 rad: Newton steps on the chain finish it; a miss by more is no root.
            if errors.largest() > POLISH_FROM * POLISH_FROM {
                return None;
            }
            *q = self.polish(target, q)?;
            errors = Misses::of(&self.pose(q), target);
            if errors.largest() > CHECK * CHECK {
                return None;
            }
        }
        Some(errors)
    }

    /// The pose `candidate` reaches, by trigonometry on its angles (then moved by its slides,
    /// for a prismatic base).
    pub(super) fn pose_of(&self, form: &ClosedForm, candidate: &Candidate) -> Frame {
        let pose = self.pose_by_trig(&candidate.angles);
        if form.fit.family == Family::PrismaticBase {
            prismatic_base::slid(form, &candidate.values, pose)
        } else {
            pose
        }
    }
}

/// How far a pose misses a target, squared: the position error (m²) and the rotation angle
/// between them (rad²).
#[derive(Clone, Copy, Debug)]
pub(super) struct Misses {
    position: f64,
    rotation: f64,
}

impl Misses {
    /// The angle is read from the matrices' difference (`‖R₁ − R₂‖_F = 2√2·sin(θ/2)`, so
    /// `θ² ≈ ‖R₁ − R₂‖²_F / 2` for the small angles that matter), which needs no logarithm.
    pub fn of(reached: &Frame, target: &Frame) -> Self {
        Self {
            position: (reached.translation.vector - target.translation.vector).norm_squared(),
            rotation: 0.5 * (reached.rotation.matrix() - target.rotation.matrix()).norm_squared(),
        }
    }

    /// From [`Chain::misses_by_trig`]'s squared errors.
    fn of_flange((position, frobenius): (f64, f64)) -> Self {
        Self {
            position,
            rotation: 0.5 * frobenius,
        }
    }

    /// True if their square roots sum (m + rad) to less than `limit`; the roots are taken
    /// only if neither alone reaches it.
    pub fn closer_than(&self, limit: f64) -> bool {
        let square = limit * limit;
        self.position < square
            && self.rotation < square
            && crate::math::sqrt(self.position) + crate::math::sqrt(self.rotation) < limit
    }

    /// The larger of the two.
    pub(super) fn largest(&self) -> f64 {
        self.position.max(self.rotation)
    }

    /// True if both errors are below `tolerance`; then written (unsquared) to `solution`, as
    /// reached without Newton steps.
    fn report_within(&self, tolerance: f64, solution: &mut IkSolution) -> bool {
        let limit = tolerance * tolerance;
        let within = self.position < limit && self.rotation < limit;
        if within {
            solution.iterations = 0;
            solution.position_error = crate::math::sqrt(self.position);
            solution.orientation_error = crate::math::sqrt(self.rotation);
        }
        within
    }
}

/// `angle` plus the whole number of turns that puts it within `[lo, hi]` nearest to
/// `reference`; `None` if no turn fits.
pub(super) fn nearest_turn(angle: f64, reference: f64, lo: f64, hi: f64) -> Option<f64> {
    use core::f64::consts::{PI, TAU};
    // Within π of the reference: if it fits, no other turn is nearer. A solver's angle lies
    // within a turn and a half of the reference (one turn or none); others take the whole turns
    // rounded by a saturating conversion (one instruction on the Cortex-M7; `libm::round` is
    // about 35): whole turns beyond ±2³¹ only saturate, and no such angle fits any limit anyway.
    let away = reference - angle;
    let near = if away.abs() < PI {
        angle
    } else if away.abs() < 3.0 * PI {
        angle + TAU.copysign(away)
    } else {
        let turns = away / TAU;
        angle + TAU * f64::from((turns + 0.5f64.copysign(turns)) as i32)
    };
    if lo <= near && near <= hi {
        return Some(near);
    }
    // Outside on one side: the next turn towards the range is the only nearer candidate.
    let next = if near > hi { near - TAU } else { near + TAU };
    (lo <= next && next <= hi).then_some(next)
}
