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

use super::closed_form::{Branch, Candidate, Candidates, Known, Shoulder, known_angle};
use super::family::ClosedForm;
use nalgebra::Vector3;

use super::subproblems::{Angle, rotate, sp1, sp3, sp4};
use crate::MAX_JOINTS;
use crate::math::Frame;

/// Every candidate solution for `target` (unchecked: the caller applies limits and FK), or
/// with `nearest` the one that takes the root nearest `free` at every choice. `free` also
/// gives the value of a joint left free by a singularity; `known`, its angles if the caller has
/// them.
pub(super) fn solve(
    form: &ClosedForm,
    target: &Frame,
    (free, known): (&[f64; MAX_JOINTS], Known),
    nearest: bool,
    out: &mut Candidates,
) {
    let s = &form.screws;
    let slack = form.slack();
    let [h1, h, h3, h4, h5, h6, _, _] = &s.axis;
    let [o1, o2, o3, o4, _, _, _, _] = &s.point;
    let c = &form.centre;
    // The senses of axes 3 and 4 along axis 2's (the ideal model's are exactly ±h).
    let (sense3, sense4) = (h3.dot(h), h4.dot(h));
    // R1 ⋯ R6, used on vectors only.
    let Shoulder { tool, v, roots } =
        Shoulder::of(form, target, (free[0], known_angle(known, 0)), nearest);
    let tool_h6 = tool * h6;
    let (shoulders, n1) = roots;
    for &(a1, b1) in shoulders.iter().take(n1) {
        let v1 = a1.value();
        let back1 = a1.negated();
        // m = R1ᵀ R1 ⋯ R6 = R2 ⋯ R6, and hᵀ R2 R3 R4 = hᵀ: hᵀ m h6 = hᵀ R5 h6.
        let m = |x: &Vector3<f64>| rotate(h1, &back1, &(tool * x));
        let m_h6 = rotate(h1, &back1, &tool_h6);
        let mt_h = tool.transpose() * rotate(h1, &a1, h);
        let (wrists, n5) =
            sp4(h, h5, h6, h.dot(&m_h6), slack).list(free[4], known_angle(known, 4), nearest);
        for &(a5, b5) in wrists.iter().take(n5) {
            let back5 = a5.negated();
            // R6 mᵀ h = R5ᵀ h
            let a6 = sp1(h6, &mt_h, &rotate(h5, &back5, h)).unwrap_or_else(|| Angle::of(free[5]));
            let (v5, v6) = (a5.value(), a6.value());
            let back6 = a6.negated();
            // planar = R2 R3 R4 = m R6ᵀ R5ᵀ, on the two vectors that matter.
            let planar_c = m(&rotate(h6, &back6, &rotate(h5, &back5, &(c - o4))));
            let planar_h5 = m(&rotate(h6, &back6, h5));
            // R2 R3 R4 = R(h, θ2 ± θ3 ± θ4).
            let Some(sum) = sp1(h, h5, &planar_h5) else {
                continue;
            };
            let sum_value = sum.value();
            let u = rotate(h1, &back1, &v) + o1 - planar_c - o2;
            let (elbows, n3) = sp3(h3, &(o4 - o3), &(o2 - o3), u.norm_squared(), slack).list(
                free[2],
                known_angle(known, 2),
                nearest,
            );
            for &(a3, b3) in elbows.iter().take(n3) {
                let reach = (o3 - o2) + rotate(h3, &a3, &(o4 - o3));
                let a2 = sp1(h, &reach, &u).unwrap_or_else(|| Angle::of(free[1]));
                let arm = a2.plus(&a3.signed(sense3));
                let a4 = sum.plus(&arm.negated()).signed(sense4);
                // θ4's value by the same arithmetic: one `atan2` per wrist, not per elbow
                // (the turn is the caller's to choose).
                let (v2, v3) = (a2.value(), a3.value());
                let v4 = sense4 * (sum_value - v2 - sense3 * v3);
                let known = [v1, v2, v3, v4, v5, v6];
                let angles = [a1, a2, a3, a4, a5, a6];
                let branch = Branch::from_roots(b1, b3, b5);
                // A full list only drops further roots, which cannot occur (8 at most).
                let _ = out.push(Candidate::new(angles, known, branch));
            }
        }
    }
}
