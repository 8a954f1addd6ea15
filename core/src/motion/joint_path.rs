//! Checking a joint move before it starts: the tool's way along the straight line in joint
//! space must not enter an exclusion box (one the tool is not already in) nor leave the
//! workspace bounds (if it starts within them). The way is sampled by FK as densely as a
//! Cartesian line's check ([`LINE_SAMPLES`]), and each piece between samples is checked
//! against the boxes exactly (segment against box).

use super::Refusal;
use super::reach::LINE_SAMPLES;
use super::workspace::Workspace;
use crate::kinematics::{Chain, Joints};

/// Refuses the joint move from `from` to `to` if the tool would enter a box or leave the
/// bounds on the way, with where (percent of the way).
pub fn check_joint_path(
    chain: &Chain,
    workspace: &Workspace,
    from: &Joints,
    to: &Joints,
) -> Result<(), Refusal> {
    let Ok(start) = chain.forward(from) else {
        return Ok(());
    };
    let origin = start.translation.vector;
    let inside_bounds = workspace.within_bounds(&origin);
    let mut last = origin;
    let mut q = *from;
    for k in 1..=LINE_SAMPLES {
        let f = k as f64 / LINE_SAMPLES as f64;
        for ((q, a), b) in q.iter_mut().zip(from.iter()).zip(to.iter()) {
            *q = a + f * (b - a);
        }
        let Ok(pose) = chain.forward(&q) else {
            return Ok(());
        };
        let p = pose.translation.vector;
        if let Some(at) = workspace.first_new_box(&last, &p, &origin) {
            let fraction = (k as f64 - 1.0 + at) / LINE_SAMPLES as f64;
            return Err(Refusal::CrossesBox(percent(fraction)));
        }
        if inside_bounds && !workspace.within_bounds(&p) {
            return Err(Refusal::OutsideWorkspace);
        }
        last = p;
    }
    Ok(())
}

/// A fraction of the way as a whole percentage, 1..=99 short of the end.
fn percent(fraction: f64) -> u8 {
    // Saturating cast: NaN and negatives become 0.
    ((fraction * 100.0) as u8).clamp(1, 99)
}
