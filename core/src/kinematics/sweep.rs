//! How far any point of the arm can move between two joint configurations: the bound the
//! joint-path check (`motion/joint_path.rs`) subdivides with, so that it cannot miss a box
//! between the points it evaluates, and that other checks of the arm's sweep can share.
//!
//! A revolute joint turning by `Δq` moves a point at distance `r` from its axis along an arc
//! of length `|Δq|·r`; a prismatic joint moves everything beyond it by `|Δq|`. The distance
//! from joint i's axis to any point of the chain beyond it (link origins, the straight
//! segments between them, the tool) is at most its *lever arm*: the lengths of every
//! translation after it (`|a|` and `|d|` of each later link, `|d|` of a later prismatic joint
//! at the larger end of its range, and the tool's offset), whatever the configuration. So
//! along the straight joint-space path from `q_a` to `q_b`, every point of the chain travels
//! at most `Σ |Δq_i|·lever_i` (revolute) `+ Σ |Δq_i|` (prismatic): [`Levers::bound`]. A point
//! of such a path is then within half that of the chord between its ends (it is within the
//! path's length of each end, measured along the path).

use super::Chain;
use crate::MAX_JOINTS;
use crate::math::Joints;

/// Each joint's lever arm (m; 1 for a prismatic joint: it moves the chain by its own travel).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Levers {
    arm: [f64; MAX_JOINTS],
    n: usize,
}

impl Levers {
    /// The lever arms of `chain`'s joints.
    pub fn of(chain: &Chain) -> Self {
        let n = chain.dof();
        let tool = chain.tool_offset();
        let mut arm = [0.0; MAX_JOINTS];
        // From the tool inwards: what lies beyond joint i is link i's own d (along its axis,
        // so no lever), then every later link's a and d, then the tool.
        let mut beyond = tool;
        for i in (0..n).rev() {
            if let Some(slot) = arm.get_mut(i) {
                *slot = if chain.is_prismatic(i) { 1.0 } else { beyond };
            }
            beyond += chain.link_reach(i);
        }
        Self { arm, n }
    }

    /// The lever arm of each joint.
    pub fn arms(&self) -> &[f64] {
        self.arm.get(..self.n).unwrap_or(&[])
    }

    /// The most any point of the chain travels (m) along the straight joint-space path from
    /// `from` to `to`: `Σ |Δq_i|·lever_i`. Every point of that path lies within half of it
    /// of the chord between the two ends' positions. (NaN in, NaN out: callers refuse it.)
    pub fn bound(&self, from: &Joints, to: &Joints) -> f64 {
        from.iter()
            .zip(to.iter())
            .zip(self.arms())
            .map(|((a, b), arm)| libm::fabs(b - a) * arm)
            .sum()
    }

    /// The most any point of the chain moves per unit of joint-space distance (Euclidean,
    /// rad or m): `√(Σ lever_i²)`, by Cauchy–Schwarz on [`bound`](Self::bound). A joint
    /// blend that passes within a tolerance τ of its via point keeps every point of the chain
    /// within τ times this of the unblended path.
    pub fn per_joint_distance(&self) -> f64 {
        crate::math::sqrt(self.arms().iter().map(|a| a * a).sum())
    }
}
