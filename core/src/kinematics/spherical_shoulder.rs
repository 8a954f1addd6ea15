//! The closed form of [`Family::SphericalShoulder`](super::Family::SphericalShoulder): seven
//! or eight joints, axes 1–3 meeting in the shoulder point, axes 5 to the last meeting in the
//! wrist centre (iiwa14, ranger-mk2).
//!
//! The arm is redundant, so θ3 (and θ5 on eight joints) are parameters: they keep the value
//! the caller puts in the reference (the present joints unless it chooses another). The
//! shoulder point stays where it is whatever θ1–θ3 do, and the wrist centre moves with θ1–θ4
//! only, so their distance depends on θ4 alone (subproblem 3). With θ3 and θ4 known, θ1 and θ2
//! turn the shoulder–wrist vector onto the target's (subproblem 2). The wrist's last three
//! joints then produce the remaining rotation: the first two point the last axis (subproblem
//! 2), the last turns about it (subproblem 1). Up to 2 · 2 · 2 = 8 solutions for each value of
//! the parameters.

use nalgebra::{Matrix3, Vector3};

use super::chain::Chain;
use super::closed_form::{Branch, BranchSolution, Candidate, Candidates};
use super::family::{ClosedForm, Family};
use super::ik::IkError;
use super::screws::misalignment;
use super::subproblems::{Angle, PairRoots, Roots, rotate, sp1, sp2, sp3};
use crate::MAX_JOINTS;
use crate::math::Frame;

/// A vector within this angle (sine) of a joint's axis counts as on it: the joint is free and
/// keeps the reference's value (the arm stretched along axis 1, or the wrist's last axis in
/// line with its first). Subproblem 2's roots are meaningless there (its other angle must turn
/// by less than that, which rounding hides); the candidate misses by about this much and is
/// polished by Newton steps before the FK check.
const NEARLY_ON_AXIS: f64 = 1e-6;

/// Up to two roots of a pair of joints, each with its branch index.
type PairList = ([(Angle, Angle, u8); 2], usize);

/// Every candidate solution for `target` on a chain of `dof` joints (unchecked: the caller
/// applies limits and FK), or with `nearest` the one that takes the root nearest `free` at
/// every choice. `free` gives the redundancy parameters θ3 (and θ5) and the value of a joint
/// left free by a singularity.
pub(super) fn solve(
    form: &ClosedForm,
    dof: usize,
    target: &Frame,
    free: &[f64; MAX_JOINTS],
    nearest: bool,
    out: &mut Candidates,
) {
    let s = &form.screws;
    let slack = form.slack();
    let [h1, h2, h3, h4, h5, _, _, _] = &s.axis;
    let (shoulder, o4, w) = (&s.point[0], &s.point[3], &form.centre);
    let (tool, d) = wrist_target(form, target);
    let (elbows, n4) = elbow_roots(form, &d).list(free[3], None, nearest);
    let a3 = Angle::of(free[2]);
    // Eight joints: θ5 is a parameter too, and the wrist's last three joints are 6–8.
    let a5 = (dof == 8).then(|| Angle::of(free[4]));
    let unit = Angle::of(0.0);
    for &(a4, b4) in elbows.iter().take(n4) {
        let elbow_wrist = o4 + rotate(h4, &a4, &(w - o4)) - shoulder;
        let u = rotate(h3, &a3, &elbow_wrist);
        let (pairs, n1) = shoulder_roots(h1, h2, &u, &d, free, nearest, slack);
        for &(a1, a2, b1) in pairs.iter().take(n1) {
            // (R1 R2 R3 R4 [R5])ᵀ R1 ⋯ Rn: what the wrist's last three joints must produce.
            let back = |x: &Vector3<f64>| {
                let x = rotate(h1, &a1.negated(), &(tool * x));
                let x = rotate(h2, &a2.negated(), &x);
                let x = rotate(h4, &a4.negated(), &rotate(h3, &a3.negated(), &x));
                a5.map_or(x, |a5| rotate(h5, &a5.negated(), &x))
            };
            let (first, reference) = if a5.is_some() {
                (5, (free[5], free[6]))
            } else {
                (4, (free[4], free[5]))
            };
            let wrist = [first, first + 1, first + 2];
            let (wrists, n6) = rotation_roots(form, wrist, (&back, false), reference, nearest);
            for &(wa, wb, wc, bw) in wrists.iter().take(n6) {
                let mut angles = [a1, a2, a3, a4, wa, wb, wc, unit];
                let mut known = [f64::NAN; MAX_JOINTS];
                known[2] = free[2];
                if let Some(a5) = a5 {
                    angles = [a1, a2, a3, a4, a5, wa, wb, wc];
                    known[4] = free[4];
                }
                let branch = Branch::from_roots(b1, b4, bw);
                // A full list only drops further roots, which cannot occur (8 at most).
                let _ = out.push(Candidate::of_joints(angles, known, branch));
            }
        }
    }
}

/// `R1 ⋯ Rn` (the target's rotation relative to the tool's at q = 0), and where the target
/// puts the wrist centre relative to the shoulder point.
fn wrist_target(form: &ClosedForm, target: &Frame) -> (Matrix3<f64>, Vector3<f64>) {
    let s = &form.screws;
    let tool = target.rotation.matrix() * s.tool_rotation.transpose();
    let d = target.translation.vector - tool * (s.tool_position - form.centre) - s.point[0];
    (tool, d)
}

/// θ4 with `‖W(θ4) − S‖ = ‖d‖` (subproblem 3, on the squares).
fn elbow_roots(form: &ClosedForm, d: &Vector3<f64>) -> Roots {
    let s = &form.screws;
    let (shoulder, h4, o4) = (&s.point[0], &s.axis[3], &s.point[3]);
    sp3(
        h4,
        &(form.centre - o4),
        &(shoulder - o4),
        d.norm_squared(),
        form.slack(),
    )
}

/// False if no value of the redundancy parameters gives `target` a solution because the
/// elbow cannot set the shoulder–wrist distance it needs (which no parameter changes): then
/// a sweep of the parameters is futile.
pub(super) fn elbow_reaches(form: &ClosedForm, target: &Frame) -> bool {
    let (_, d) = wrist_target(form, target);
    elbow_roots(form, &d) != Roots::None
}

/// θ1, θ2 with `R1 R2 u = d` (subproblem 2 as `R2 u = R1ᵀ d`). A `d` along axis 1 leaves θ1
/// free, a `u` along axis 2 leaves θ2 free: each keeps `free`'s value.
fn shoulder_roots(
    h1: &Vector3<f64>,
    h2: &Vector3<f64>,
    u: &Vector3<f64>,
    d: &Vector3<f64>,
    free: &[f64; MAX_JOINTS],
    nearest: bool,
    slack: f64,
) -> PairList {
    let unit = Angle::of(0.0);
    let mut list = ([(unit, unit, 0); 2], 0);
    let single = |a1: Angle| {
        let a2 = sp1(h2, u, &rotate(h1, &a1.negated(), d)).unwrap_or_else(|| Angle::of(free[1]));
        ([(a1, a2, 0), (unit, unit, 0)], 1)
    };
    if misalignment(h1, &d.normalize()) <= NEARLY_ON_AXIS {
        return single(Angle::of(free[0]));
    }
    match sp2(h2, u, h1, d, slack) {
        PairRoots::Some(pairs, count) => {
            let (r1, r2) = (Angle::of(free[0]), Angle::of(free[1]));
            let closeness =
                |(t2, t1): &(Angle, Angle)| t1.negated().closeness(&r1) + t2.closeness(&r2);
            for (i, (t2, t1)) in (0u8..).zip(pairs.iter().take(count)) {
                if let Some(slot) = list.0.get_mut(usize::from(i)) {
                    *slot = (t1.negated(), *t2, i);
                }
            }
            list.1 = count;
            if nearest && count == 2 {
                let [first, second] = pairs;
                let pick = usize::from(closeness(&second) > closeness(&first));
                list.0.swap(0, pick);
                list.1 = 1;
            }
            list
        }
        PairRoots::FreeFirst => {
            // u on axis 2: θ2 keeps its value, θ1 turns u onto d.
            sp1(h1, u, d).map_or(list, single)
        }
        PairRoots::None => list,
    }
}

/// The rotations about three axes `[a, b, c]` (axis indices; b ∦ a, c) producing the rotation
/// `m` (given by its action `back` on vectors): `R(ha, θa) R(hb, θb) R(hc, θc) = m` — the
/// wrist's last three joints of a spherical shoulder, or θ3, θ4 + θ5 and θ6 of a prismatic
/// base. Axis c must point along `m hc`: `R(ha, −θa) m hc = R(hb, θb) hc` (subproblem 2); θc
/// then turns `hb` onto `(Ra Rb)ᵀ m hb` (subproblem 1). `(ra, rb)`: the reference values of
/// θa and θb (θa keeps `ra` where it is free; with `nearest`, the pair nearest them).
/// `m_exact`: `m` is the target's own (no root solved before it), so a tilt of `m hc` off `ha`
/// above rounding is the target's, and subproblem 2 solves it down to 1e-12; otherwise it may
/// be the error of an earlier tangent root (~1e-8) and, up to [`NEARLY_ON_AXIS`], leaves θa
/// free.
pub(super) fn rotation_roots(
    form: &ClosedForm,
    [a, b, c]: [usize; 3],
    (back, m_exact): (&impl Fn(&Vector3<f64>) -> Vector3<f64>, bool),
    (ra, rb): (f64, f64),
    nearest: bool,
) -> ([(Angle, Angle, Angle, u8); 2], usize) {
    let axes = &form.screws.axis;
    let unit = Angle::of(0.0);
    let mut out = ([(unit, unit, unit, 0); 2], 0);
    let (Some(ha), Some(hb), Some(hc)) = (axes.get(a), axes.get(b), axes.get(c)) else {
        return out;
    };
    let (m_hb, m_hc) = (back(hb), back(hc));
    let mut push = |aa: Angle, ab: Angle, bit: u8| {
        let rest = rotate(hb, &ab.negated(), &rotate(ha, &aa.negated(), &m_hb));
        if let (Some(ac), Some(slot)) = (sp1(hc, hb, &rest), out.0.get_mut(out.1)) {
            *slot = (aa, ab, ac, bit);
            out.1 += 1;
        }
    };
    let roots = if !m_exact && misalignment(ha, &m_hc) <= NEARLY_ON_AXIS {
        PairRoots::FreeFirst
    } else {
        sp2(ha, &m_hc, hb, hc, form.slack())
    };
    match roots {
        PairRoots::Some(pairs, count) => {
            let (ra, rb) = (Angle::of(-ra), Angle::of(rb));
            let closeness = |(ta, tb): &(Angle, Angle)| ta.closeness(&ra) + tb.closeness(&rb);
            let skip = match pairs {
                [one, two] if nearest && count == 2 => {
                    usize::from(closeness(&two) > closeness(&one))
                }
                _ => 0,
            };
            let take = if nearest { 1 } else { count };
            for (bit, (ta, tb)) in (0u8..).zip(pairs.iter()).skip(skip).take(take) {
                push(ta.negated(), *tb, bit);
            }
        }
        PairRoots::FreeFirst => {
            // Axis c along axis a (the wrist stretched): θa + θc is fixed, θa keeps `ra`.
            let aa = Angle::of(ra);
            if let Some(ab) = sp1(hb, hc, &rotate(ha, &aa.negated(), &m_hc)) {
                push(aa, ab, 0);
            }
        }
        PairRoots::None => {}
    }
    out
}

/// Steps of a sweep across one redundancy parameter's range: 16 for θ3 alone, 8 · 8 for θ3
/// and θ5.
const SWEEP: [usize; 2] = [16, 8];

/// How many references [`swept`] gives at most.
pub(super) const SWEEP_TRIES: usize = 64;

/// The joints (0-based) that are the redundancy parameters on a chain of `dof` joints: θ3,
/// and θ5 on eight.
fn parameters(dof: usize) -> &'static [usize] {
    if dof == 8 { &[2, 4] } else { &[2] }
}

impl Chain {
    /// The joints (0-based) whose values are the redundancy parameters of the closed form: θ3
    /// (index 2) on a seven-joint arm, θ3 and θ5 (2, 4) on eight; none on a chain without a
    /// redundant closed form.
    pub fn redundancy_parameters(&self) -> &'static [usize] {
        match self.closed_form() {
            Some(form) if form.fit.family == Family::SphericalShoulder => parameters(self.dof()),
            _ => &[],
        }
    }

    /// The solution nearest `reference` (on `branch` if given) that keeps the reference's
    /// values of the redundancy parameters: [`solve_nearest`](Self::solve_nearest) without
    /// its sweep, for a caller that chose them. `None` if those values have none.
    pub fn solve_nearest_keeping(
        &self,
        target: &Frame,
        reference: &[f64],
        branch: Option<Branch>,
    ) -> Result<Option<BranchSolution>, IkError> {
        let mut checked = [0.0; MAX_JOINTS];
        self.prepare(target, reference, &mut checked)?;
        Ok(self
            .nearest_for(target, &checked, branch)?
            .map(|e| e.solution))
    }
}

/// The `k`-th reference of a sweep of the redundancy parameters across their ranges, from the
/// reference's own values outwards: each parameter moved by 0, +1, −1, +2, … steps of
/// 1/[`SWEEP`] of its range (wrapped within it). `None` past the sweep's end.
pub(super) fn swept(
    chain: &Chain,
    reference: &[f64; MAX_JOINTS],
    k: usize,
) -> Option<[f64; MAX_JOINTS]> {
    let parameters = parameters(chain.dof());
    let steps = if chain.dof() == 8 { SWEEP[1] } else { SWEEP[0] };
    let (min, max) = (chain.min(), chain.max());
    let mut out = *reference;
    let mut rest = k;
    for &p in parameters {
        let i = rest % steps;
        rest /= steps;
        let (lo, hi) = (*min.get(p)?, *max.get(p)?);
        let range = (hi - lo).min(core::f64::consts::TAU);
        // 0, +1, −1, +2, −2, …
        let offset = if i % 2 == 1 {
            (i / 2 + 1) as f64
        } else {
            -((i / 2) as f64)
        };
        let v = out.get(p)? + offset * range / steps as f64;
        *out.get_mut(p)? = v - range * libm::floor((v - lo) / range);
    }
    (rest == 0).then_some(out)
}
