//! The chain at its zero configuration as joint axes through reference points (product of
//! exponentials): the form the closed-form solvers work in.
//!
//! Joint `i` turns everything beyond it about the line through `point[i]` along `axis[i]`
//! (base coordinates at q = 0), so the tool pose is `g1(q1) ∘ … ∘ gn(qn)` applied to the tool's
//! zero pose. A reference point may slide along its axis without changing anything, which is
//! how the solvers place it where two axes meet.

use nalgebra::{Matrix3, Vector3};

use super::chain::{Axes, Chain};
use crate::MAX_JOINTS;

/// Joint axes, reference points and the tool pose at the zero configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Screws {
    pub axis: [Vector3<f64>; MAX_JOINTS],
    pub point: [Vector3<f64>; MAX_JOINTS],
    /// The tool's rotation at q = 0.
    pub tool_rotation: Matrix3<f64>,
    /// The tool's position at q = 0.
    pub tool_position: Vector3<f64>,
}

impl Screws {
    /// The screws of `chain` (its base frame included).
    pub fn of(chain: &Chain) -> Self {
        let mut axes = Axes::default();
        let tool = chain.tool_and_axes(&[0.0; MAX_JOINTS], &mut axes);
        Self {
            axis: axes.z,
            point: axes.origin,
            tool_rotation: *tool.rotation.matrix(),
            tool_position: tool.translation.vector,
        }
    }
}

/// The midpoint of the shortest segment between two lines and its length; `None` for
/// (nearly) parallel lines.
pub(super) fn closest_meeting(
    p1: &Vector3<f64>,
    h1: &Vector3<f64>,
    p2: &Vector3<f64>,
    h2: &Vector3<f64>,
) -> Option<(Vector3<f64>, f64)> {
    let c = h1.dot(h2);
    let s2 = 1.0 - c * c;
    if s2 < 1e-12 {
        return None;
    }
    let d = p2 - p1;
    let (a, b) = (h1.dot(&d), h2.dot(&d));
    let t1 = (a - c * b) / s2;
    let t2 = (c * a - b) / s2;
    let (x1, x2) = (p1 + h1 * t1, p2 + h2 * t2);
    Some(((x1 + x2) * 0.5, (x1 - x2).norm()))
}

/// The distance from `x` to the line through `p` along the unit `h`.
pub(super) fn distance_to_line(x: &Vector3<f64>, p: &Vector3<f64>, h: &Vector3<f64>) -> f64 {
    let d = x - p;
    (d - h * h.dot(&d)).norm()
}

/// The sine of the angle between two unit axes (0 for parallel or anti-parallel ones).
pub(super) fn misalignment(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    a.cross(b).norm()
}
