//! Checking a joint move before it starts: the tool's way along the straight line in joint
//! space must not enter an exclusion box (one the tool is not already in) nor leave the
//! workspace bounds (if it starts within them).
//!
//! The way is a curve. It is evaluated by FK at points along it and each piece between two
//! points is checked as its chord, against the boxes grown (and the bounds shrunk) by how far
//! the curve can stray from that chord: half of [`Levers::bound`] over the piece, from the
//! joints' steps and the chain's lever arms. A piece whose chord comes that close to a box or
//! a bound is halved, down to [`MIN_PIECE`] of the way, so nothing between the points can be
//! missed (16 fixed chords missed a long joint-1 move's arc bulging 47 mm on ranger-mk1, 65 mm
//! on ur5, issue 33). The work is bounded: at most [`PATH_EVALUATIONS`] FK evaluations a
//! check; a way that needs more (one that grazes a box or a bound) is refused `near edge`
//! rather than checked without end.

use armgate_protocol::client::PathPoint;

use super::Refusal;
use super::reach::LINE_SAMPLES;
use super::workspace::Workspace;
use crate::kinematics::{Chain, Joints, Levers};
use crate::math::Vector3;

/// FK evaluations one joint-path check may make at most (the pieces tried, halved ones
/// included). The worst case on the Cortex-M7 is printed by qemu-bench ("joint path check").
pub const PATH_EVALUATIONS: usize = 512;
/// The shortest piece tried, as a fraction of the way.
pub const MIN_PIECE: f64 = 1.0 / 65_536.0;

/// Refuses the joint move from `from` to `to` if the tool could enter a box or leave the
/// bounds on the way, with where (percent of the way); `clearance` (m, ≥ 0) is kept from
/// both besides (what a blend at either end may stray from the straight way).
pub fn check_joint_path(
    chain: &Chain,
    workspace: &Workspace,
    from: &Joints,
    to: &Joints,
    clearance: f64,
) -> Result<(), Refusal> {
    let way = Way {
        chain,
        workspace,
        from,
        to,
    };
    let Some(origin) = way.tool_at(0.0) else {
        return Ok(());
    };
    let inside_bounds = workspace.within_bounds(&origin);
    // How far the tool can stray from a piece's chord, per fraction of the way.
    let stray = 0.5 * Levers::of(chain).bound(from, to);
    let longest = 1.0 / LINE_SAMPLES as f64;
    let (mut done, mut step, mut last) = (0.0_f64, longest, origin);
    for _ in 0..PATH_EVALUATIONS {
        if done >= 1.0 {
            return Ok(());
        }
        let next = (done + step).min(1.0);
        let Some(p) = way.tool_at(next) else {
            return Ok(());
        };
        let margin = stray * (next - done) + clearance;
        let near_box = workspace.first_new_box_near(&last, &p, &origin, margin);
        let near_bounds = inside_bounds
            && !(workspace.within_bounds_by(&last, margin)
                && workspace.within_bounds_by(&p, margin));
        if near_box.is_none() && !near_bounds {
            (done, last) = (next, p);
            step = (step * 2.0).min(longest);
        } else if step > MIN_PIECE {
            step *= 0.5;
        } else {
            return Err(way.diagnose(done, &last, &origin, inside_bounds));
        }
    }
    if done >= 1.0 {
        Ok(())
    } else {
        Err(Refusal::NearEdge(PathPoint::at(done)))
    }
}

/// The straight joint-space way being checked.
struct Way<'a> {
    chain: &'a Chain,
    workspace: &'a Workspace,
    from: &'a Joints,
    to: &'a Joints,
}

impl Way<'_> {
    /// The tool's position a fraction `s` of the way along (`None` if the FK refuses).
    fn tool_at(&self, s: f64) -> Option<Vector3<f64>> {
        let mut q = *self.from;
        for ((q, a), b) in q.iter_mut().zip(self.from.iter()).zip(self.to.iter()) {
            *q = a + s * (b - a);
        }
        let pose = self.chain.forward(&q).ok()?;
        Some(pose.translation.vector)
    }

    /// Why the way cannot be shown clear beyond `done` (the tool at `last`): it enters a box
    /// or leaves the bounds a little further on (looked for at doubling distances, at most
    /// [`DIAGNOSIS_EVALUATIONS`] FK evaluations), or it comes too near one to tell.
    fn diagnose(
        &self,
        done: f64,
        last: &Vector3<f64>,
        origin: &Vector3<f64>,
        inside_bounds: bool,
    ) -> Refusal {
        let mut ahead = MIN_PIECE;
        for _ in 0..DIAGNOSIS_EVALUATIONS {
            let next = (done + ahead).min(1.0);
            let Some(p) = self.tool_at(next) else { break };
            if let Some(at) = self.workspace.first_new_box_near(last, &p, origin, 0.0) {
                return Refusal::CrossesBox(percent(done + at * (next - done)));
            }
            if inside_bounds && !self.workspace.within_bounds(&p) {
                return Refusal::OutsideWorkspace;
            }
            if next >= 1.0 {
                break;
            }
            ahead *= 2.0;
        }
        Refusal::NearEdge(PathPoint::at(done))
    }
}

/// FK evaluations to tell a way that enters a box or leaves the bounds from one that only
/// comes near: from [`MIN_PIECE`] ahead, doubling, to the end of the way.
const DIAGNOSIS_EVALUATIONS: usize = 17;

/// A fraction of the way as a whole percentage, 1..=99 short of the end.
fn percent(fraction: f64) -> u8 {
    // Saturating cast: NaN and negatives become 0.
    ((fraction * 100.0) as u8).clamp(1, 99)
}
