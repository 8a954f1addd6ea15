//! The closed form of [`Family::SphericalWrist`](super::Family::SphericalWrist): axes 2 and 3
//! parallel, axes 4–6 meeting in the wrist centre.
//!
//! The wrist centre moves with joints 1–3 only, so the position is solved first: rotations
//! about axes 2 and 3 keep the component along their common direction, which gives θ1
//! (subproblem 4); the distance from axis 2's point to the wrist centre depends on θ3 alone
//! (subproblem 3); θ2 turns one known vector onto another (subproblem 1). The wrist then
//! produces the remaining rotation: θ4, θ5 from where axis 6 must point (subproblem 2), θ6
//! from what is left (subproblem 1). Up to 2 · 2 · 2 = 8 solutions.

use nalgebra::Vector3;

use super::closed_form::{Branch, Candidate, Candidates, Gate, Known, Shoulder, known_angle};
use super::family::{ClosedForm, Fixed};
use super::subproblems::{Angle, Mirror, PairRoots, rotate, sp1, sp2_solving};
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
    let [h1, h2, h3, _, h5, h6, _, _] = &s.axis;
    let [o1, o2, _, _, _, _, _, _] = &s.point;
    let Shoulder { tool, v, roots } =
        Shoulder::of(form, target, (free[0], known_angle(known, 0)), nearest);
    // Only the action of R1 ⋯ R6 on h5 and h6 is needed.
    let (tool_h5, tool_h6) = (tool * h5, tool * h6);
    // The sense of axis 3 along axis 2's (the ideal model's is exactly ±h2): R2 R3 is one
    // rotation about h2.
    let sense3 = h3.dot(h2);
    // θ3 from the distance between axis 2's point and the wrist centre.
    let Some(Fixed { elbow, mirror, .. }) = &form.fixed else {
        return;
    };
    // Only a solve for every root has a second wrist root to mirror.
    let mirror = mirror.filter(|_| !nearest);
    let (shoulders, n1) = roots;
    for &(a1, b1) in shoulders.iter().take(n1) {
        let Some(v1) = gate.admit(0, a1.value()) else {
            continue;
        };
        let back1 = a1.negated();
        let (shoulder_h5, shoulder_h6) =
            (rotate(h1, &back1, &tool_h5), rotate(h1, &back1, &tool_h6));
        let u = rotate(h1, &back1, &v) - (o2 - o1);
        let choice3 = (free[2], known_angle(known, 2), nearest);
        let (elbows, n3) = elbow.roots(u.norm_squared(), slack, choice3);
        for &(a3, value3, b3) in elbows.iter().take(n3) {
            let Some(v3) = gate.admit(2, value3) else {
                continue;
            };
            let a2 = sp1(h2, &elbow.reach(&a3), &u).unwrap_or_else(|| Angle::of(free[1]));
            let Some(v2) = gate.admit(1, a2.value()) else {
                continue;
            };
            // (R1 R2 R3)ᵀ applied to the tool's h5 and h6: what the wrist must produce.
            let back23 = a2.plus(&a3.signed(sense3)).negated();
            let back = |x: &Vector3<f64>| rotate(h2, &back23, x);
            let arm = ([a1, a2, a3], [v1, v2, v3]);
            let branch = Branch::from_roots(b1, b3, 0);
            wrist(
                form,
                [back(&shoulder_h5), back(&shoulder_h6)],
                arm,
                branch,
                (free, known, nearest),
                (gate, mirror),
                out,
            );
        }
    }
}

/// Joints 4–6 producing the rotation `m = R4 R5 R6`, given as `[m h5, m h6]`, appended to the
/// arm's `[θ1, θ2, θ3]` (angles and values) if `gate` passes them. The second root is the
/// first's `mirror` where the wrist's axes allow it.
fn wrist(
    form: &ClosedForm,
    [turned_h5, pointing]: [Vector3<f64>; 2],
    arm: ([Angle; 3], [f64; 3]),
    branch: Branch,
    (free, known, nearest): (&[f64; MAX_JOINTS], Known, bool),
    (gate, mirror): (Gate, Option<Mirror>),
    out: &mut Candidates,
) {
    let [_, _, _, h4, h5, h6, _, _] = &form.screws.axis;
    // θ6 with R6 = R5ᵀ R4ᵀ m: where it takes h5.
    let last = |a4: &Angle, a5: &Angle| {
        sp1(
            h6,
            h5,
            &rotate(h5, &a5.negated(), &rotate(h4, &a4.negated(), &turned_h5)),
        )
    };
    let ([a1, a2, a3], [v1, v2, v3]) = arm;
    // A root whose values `gate` passed.
    let mut keep = |[a4, a5, a6]: [Angle; 3], [v4, v5, v6]: [f64; 3], wrist: u8| {
        let values = [v1, v2, v3, v4, v5, v6];
        let angles = [a1, a2, a3, a4, a5, a6];
        let branch = branch.with_wrist(wrist);
        // A full list only drops further roots, which cannot occur (8 at most).
        let _ = out.push(Candidate::new(angles, values, branch, gate.is_closed()));
    };
    let admit =
        |[v4, v5, v6]: [f64; 3]| Some([gate.admit(3, v4)?, gate.admit(4, v5)?, gate.admit(5, v6)?]);
    // A root solved on its own, θ5 tested first (on most arms its limits are the narrowest:
    // a root outside them needs no θ4 or θ6).
    let mut solved = |a4: Angle, a5: Angle, wrist: u8| {
        let v5 = gate.admit(4, a5.value())?;
        let v4 = gate.admit(3, a4.value())?;
        let a6 = last(&a4, &a5)?;
        let v6 = gate.admit(5, a6.value())?;
        keep([a4, a5, a6], [v4, v5, v6], wrist);
        Some(())
    };
    // R(h4, −θ4) · m h6 = R(h5, θ5) · h6 (a mirrored second root is not solved).
    let most = if mirror.is_some() { 1 } else { 2 };
    match sp2_solving(h4, &pointing, h5, h6, (form.slack(), most)) {
        PairRoots::Some([(t4, a5), _], 2) if let Some(mirror) = mirror => {
            // Both roots, the second mirroring the first (its values whether or not the gate
            // passes them); none if θ5 of neither is within its limits.
            let (a4, v5) = (t4.negated(), a5.value());
            let outside = |v: f64| gate.admit(4, v).is_none();
            if outside(v5) && outside(mirror.other_middle(v5)) {
                return;
            }
            let Some(a6) = last(&a4, &a5) else {
                return;
            };
            let first = ([a4, a5, a6], [a4.value(), v5, a6.value()]);
            let second = mirror.other(first.0, first.1);
            for (wrist, (angles, values)) in [(0, first), (1, second)] {
                if let Some(values) = admit(values) {
                    keep(angles, values, wrist);
                }
            }
        }
        PairRoots::Some(pairs, count) => {
            let skip = match pairs {
                [first, second] if nearest && count == 2 => {
                    let r4 =
                        known_angle(known, 3).map_or_else(|| Angle::of(-free[3]), Angle::negated);
                    let r5 = known_angle(known, 4).map_or_else(|| Angle::of(free[4]), |a| *a);
                    let closeness =
                        |(t4, t5): &(Angle, Angle)| t4.closeness(&r4) + t5.closeness(&r5);
                    usize::from(closeness(&second) > closeness(&first))
                }
                _ => 0,
            };
            let take = if nearest { 1 } else { count };
            for (bw, (t4, t5)) in (0u8..).zip(pairs.iter()).skip(skip).take(take) {
                let _ = solved(t4.negated(), *t5, bw);
            }
        }
        PairRoots::FreeFirst => {
            // Axis 6 along axis 4 (θ5 = 0 on most arms): θ4 + θ6 is fixed, θ4 keeps `free`.
            let a4 = Angle::of(free[3]);
            let turned = rotate(h4, &a4.negated(), &pointing);
            if let Some(a5) = sp1(h5, h6, &turned) {
                let _ = solved(a4, a5, 0);
            }
        }
        PairRoots::None => {}
    }
}
