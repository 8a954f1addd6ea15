//! The closed form of [`Family::ThreeParallel`](super::Family::ThreeParallel): axes 2, 3 and 4
//! parallel, axes 5 and 6 meeting (UR-type arms).
//!
//! The point where axes 5 and 6 meet moves with joints 1–4 only, and rotations about the three
//! parallel axes keep its component along their direction: θ1 (subproblem 4). The same
//! direction is kept by the product `R2 R3 R4`, which gives θ5 (subproblem 4) and then θ6
//! (subproblem 1) from the orientation. What is left is a planar two-link problem for the
//! origin of axis 4: θ3 (subproblem 3), θ2 (subproblem 1), and θ4 from the remaining rotation:
//! `R2 R3 R4` turns about the common direction by the (signed) sum of the three angles, found
//! once per wrist (subproblem 1), so θ4 is that sum less θ2 and θ3. Up to 2 · 2 · 2 = 8
//! solutions.

use super::closed_form::{Branch, Candidate, Candidates, Gate, Known, Shoulder, known_angle};
use super::family::{ClosedForm, Fixed};
use nalgebra::Vector3;

use super::subproblems::{Angle, rotate, sp1};
use crate::MAX_JOINTS;
use crate::math::Frame;

/// Every candidate solution for `target` that passes `gate` (unchecked: the caller checks it
/// by FK), or with `nearest` the one that takes the root nearest `free` at every choice.
/// `free` also gives the value of a joint left free by a singularity; `known`, its angles if
/// the caller has them.
// Out of line: inlined with the other families' solvers, each cost about 70 instructions more
// on the Cortex-M7 (qemu-bench), and the firmware 0.9 KB more flash.
#[inline(never)]
pub(super) fn solve(
    form: &ClosedForm,
    target: &Frame,
    (free, known): (&[f64; MAX_JOINTS], Known),
    nearest: bool,
    gate: Gate,
    out: &mut Candidates,
) {
    let s = &form.screws;
    let slack = form.slack();
    let [h1, h, h3, h4, h5, h6, _, _] = &s.axis;
    let [o1, o2, _, _, _, _, _, _] = &s.point;
    // The senses of axes 3 and 4 along axis 2's (the ideal model's are exactly ±h).
    let (sense3, sense4) = (h3.dot(h), h4.dot(h));
    // θ3 from the distance between the origins of axes 2 and 4; θ5 from hᵀ R5 h6 = hᵀ m h6
    // (below); the planar part R(h, Σ) (c − o4), one per wrist root.
    let Some(Fixed {
        elbow,
        mirror,
        parallel: Some((wrist, planar)),
    }) = &form.fixed
    else {
        return;
    };
    // R(h, Σ) R5 R6 with Σ = θ2 ± θ3 ± θ4: with every root, the second wrist root mirrors the
    // first.
    let mirror = mirror.filter(|_| !nearest);
    // R1 ⋯ R6, used on vectors only.
    let Shoulder { tool, v, roots } =
        Shoulder::of(form, target, (free[0], known_angle(known, 0)), nearest);
    let tool_h6 = tool * h6;
    let (shoulders, n1) = roots;
    for &(a1, b1) in shoulders.iter().take(n1) {
        let Some(v1) = gate.admit(0, a1.value()) else {
            continue;
        };
        let back1 = a1.negated();
        // m = R1ᵀ R1 ⋯ R6 = R2 ⋯ R6, and hᵀ R2 R3 R4 = hᵀ: hᵀ m h6 = hᵀ R5 h6.
        let m = |x: &Vector3<f64>| rotate(h1, &back1, &(tool * x));
        let m_h6 = rotate(h1, &back1, &tool_h6);
        let mt_h = tool.transpose() * rotate(h1, &a1, h);
        // Where axis 4's origin must be, less the planar part R2 R3 R4 (c − o4).
        let to_centre = rotate(h1, &back1, &v) + o1 - o2;
        let (wrists, n5) =
            wrist
                .roots(h.dot(&m_h6), slack)
                .list(free[4], known_angle(known, 4), nearest);
        // The sum Σ, θ5, θ6 (angles and values) of the first wrist root.
        let mut first: Option<([Angle; 3], [f64; 3])> = None;
        for &(a5, b5) in wrists.iter().take(n5) {
            let root = match (first, mirror) {
                (Some(first), Some(mirror)) => Some(mirror.other(first.0, first.1)),
                _ => {
                    let back5 = a5.negated();
                    // R6 mᵀ h = R5ᵀ h
                    let a6 = sp1(h6, &mt_h, &rotate(h5, &back5, h))
                        .unwrap_or_else(|| Angle::of(free[5]));
                    // R2 R3 R4 = m R6ᵀ R5ᵀ = R(h, Σ): where it takes h5 (R5ᵀ h5 = h5).
                    sp1(h, h5, &m(&rotate(h6, &a6.negated(), h5)))
                        .map(|sum| ([sum, a5, a6], [sum.value(), a5.value(), a6.value()]))
                }
            };
            let Some(([sum, a5, a6], [sum_value, v5, v6])) = root else {
                continue;
            };
            first = root;
            let (Some(v5), Some(v6)) = (gate.admit(4, v5), gate.admit(5, v6)) else {
                continue;
            };
            let u = to_centre - planar.at(&sum);
            let choice3 = (free[2], known_angle(known, 2), nearest);
            let (elbows, n3) = elbow.roots(u.norm_squared(), slack, choice3);
            for &(a3, value3, b3) in elbows.iter().take(n3) {
                let Some(v3) = gate.admit(2, value3) else {
                    continue;
                };
                let a2 = sp1(h, &elbow.reach(&a3), &u).unwrap_or_else(|| Angle::of(free[1]));
                let Some(v2) = gate.admit(1, a2.value()) else {
                    continue;
                };
                let arm = a2.plus(&a3.signed(sense3));
                let a4 = sum.plus(&arm.negated()).signed(sense4);
                // θ4's value by the same arithmetic: no `atan2` per elbow (turned by the gate).
                let Some(v4) = gate.admit(3, sense4 * (sum_value - v2 - sense3 * v3)) else {
                    continue;
                };
                let values = [v1, v2, v3, v4, v5, v6];
                let angles = [a1, a2, a3, a4, a5, a6];
                let branch = Branch::from_roots(b1, b3, b5);
                // A full list only drops further roots, which cannot occur (8 at most).
                let _ = out.push(Candidate::new(angles, values, branch, gate.is_closed()));
            }
        }
    }
}
