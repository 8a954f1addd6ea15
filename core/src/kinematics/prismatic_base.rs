//! The closed form of [`Family::PrismaticBase`](super::Family::PrismaticBase): two prismatic
//! joints (a base sliding in a plane), then four revolute joints whose axes 4 and 5 are
//! parallel (the hybrid robot: base yaw, two pitches, roll).
//!
//! The slides turn nothing, and the parallel axes 4, 5 turn by the sum φ = θ4 ± θ5, so the
//! orientation is three rotations, θ3, φ, θ6 (subproblem 2, then 1; on hybrid a z-x-z Euler
//! problem). The position's component along the normal of the slides' plane does not depend on
//! the slides; with θ3, φ and θ6 known it depends on θ4 alone (subproblem 4). The slides take
//! up the rest of the position: two linear equations. Up to 2 · 2 = 4 solutions.
//!
//! Branch bits: [`Branch::SHOULDER`] is the second root of (θ3, φ) — the base turned about
//! half a turn, the arm reaching back over it; [`Branch::ELBOW`] the second root of θ4 (θ5
//! follows from φ); [`Branch::WRIST`] is never set.

use nalgebra::Vector3;

use super::closed_form::{Branch, Candidate, Candidates, Known, known_angle};
use super::family::ClosedForm;
use super::spherical_shoulder::rotation_roots;
use super::subproblems::{Angle, rotate, sp4};
use crate::MAX_JOINTS;
use crate::math::{Frame, Joints};
use crate::saturate::saturate;

/// Every candidate solution for `target` (unchecked: the caller applies limits and FK), or
/// with `nearest` the one that takes the root nearest `free` at every choice. `free` also
/// gives the value of a joint left free by a singularity (θ3 where axis 6 points along axis 3:
/// only θ3 ± θ6 is fixed); `known`, the joints' angles if the caller has them.
pub(super) fn solve(
    form: &ClosedForm,
    target: &Frame,
    (free, known): (&[f64; MAX_JOINTS], Known),
    nearest: bool,
    out: &mut Candidates,
) {
    let s = &form.screws;
    let [h1, h2, h3, h4, h5, h6, _, _] = &s.axis;
    let [_, _, o3, _, o5, o6, _, _] = &s.point;
    let o4 = &form.centre;
    // R3 R4 R5 R6, the target's rotation relative to the tool's at q = 0 (the slides turn
    // nothing), and φ's sense: R4 R5 = R(h4, θ4 + sense5 · θ5).
    let tool = target.rotation.matrix() * s.tool_rotation.transpose();
    let sense5 = h5.dot(h4);
    let reference = (free[2], free[3] + sense5 * free[4]);
    let back = |x: &Vector3<f64>| tool * x;
    let (rotations, count) = rotation_roots(form, [2, 3, 5], (&back, true), reference, nearest);
    // The slides' plane: its normal, and the Gram matrix of its two directions.
    let normal = h1.cross(h2).normalize();
    let c12 = h1.dot(h2);
    let det = 1.0 - c12 * c12;
    let swing = o5 - o4;
    for &(a3, phi, a6, b3) in rotations.iter().take(count) {
        // The tool's position turned by θ6, then by φ about axis 5 and θ3; what is left is
        // the slides and θ4's swing of axis 5 about axis 4.
        let rolled = o6 + rotate(h6, &a6, &(s.tool_position - o6));
        let rest = target.translation.vector
            - (o3 + rotate(h3, &a3, &(o4 - o3 + rotate(h4, &phi, &(rolled - o5)))));
        // rest = q1 h1 + q2 h2 + R3 R4 (o5 − o4): along the normal, θ4 alone.
        let up = rotate(h3, &a3.negated(), &normal);
        let (elbows, n4) = sp4(&up, h4, &swing, normal.dot(&rest), form.slack()).list(
            free[3],
            known_angle(known, 3),
            nearest,
        );
        for &(a4, b4) in elbows.iter().take(n4) {
            let slid = rest - rotate(h3, &a3, &rotate(h4, &a4, &swing));
            let (along1, along2) = (h1.dot(&slid), h2.dot(&slid));
            let q1 = (along1 - c12 * along2) / det;
            let q2 = (along2 - c12 * along1) / det;
            let a5 = phi.plus(&a4.negated()).signed(sense5);
            let slide = Angle { cos: 1.0, sin: 0.0 };
            let angles = [slide, slide, a3, a4, a5, a6];
            let values = [q1, q2, f64::NAN, f64::NAN, f64::NAN, f64::NAN];
            // A full list only drops further roots, which cannot occur (4 at most).
            let _ = out.push(Candidate::new(
                angles,
                values,
                Branch::from_roots(b3, b4, 0),
                false,
            ));
        }
    }
}

/// Half the squared distance (m²) of a candidate's slides from the reference's: the prismatic
/// joints' share of the nearest-solution measure, in which a revolute joint counts
/// `1 − cos Δθ` (so a small slide counts as much as a turn of the same size).
pub(super) fn slide_distance(values: &[f64; MAX_JOINTS], reference: &[f64; MAX_JOINTS]) -> f64 {
    let (d1, d2) = (values[0] - reference[0], values[1] - reference[1]);
    0.5 * (d1 * d1 + d2 * d2)
}

/// `pose` (the chain's with its slides at 0) with the slides at `values[0]`, `values[1]`:
/// moved along their axes, which nothing before them turns.
pub(super) fn slid(form: &ClosedForm, values: &[f64; MAX_JOINTS], pose: Frame) -> Frame {
    let [h1, h2, _, _, _, _, _, _] = &form.screws.axis;
    let mut moved = pose;
    moved.translation.vector += h1 * values[0] + h2 * values[1];
    moved
}

/// The slides' `values` written to `q` (clamped into their limits) if each lies within its
/// limits widened by `widen`; false if one does not.
pub(super) fn place_slides(
    values: &[f64; MAX_JOINTS],
    q: &mut Joints,
    (min, max): (&[f64; MAX_JOINTS], &[f64; MAX_JOINTS]),
    widen: f64,
) -> bool {
    let slides = q.iter_mut().zip(values).zip(min.iter().zip(max)).take(2);
    for ((v, value), (lo, hi)) in slides {
        if !(lo - widen <= *value && *value <= hi + widen) {
            return false;
        }
        *v = saturate(*value, *lo, *hi);
    }
    true
}
