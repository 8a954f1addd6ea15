//! The last pose evaluation of a tracking solve, kept for the next solve.
//!
//! A Newton descent evaluates the tool pose and the joint axes at every iterate, the converged
//! one last. A control tick seeds the next solve with the command it sent, which is that
//! converged iterate whenever the limiter left it alone, so the next solve's first evaluation
//! is the one already made (≈ 2,000 Cortex-M7 instructions a tick, qemu-bench). The evaluation
//! is a pure function of the joints on a chain that never changes, so it is reused only for
//! joints equal bit for bit.

use super::chain::{Axes, Chain};
use crate::MAX_JOINTS;
use crate::math::Frame;

/// The tool pose and joint axes at one joint vector of one chain: the solver's working buffer,
/// which keeps the last evaluation. Use one per chain.
#[derive(Clone, Debug, Default)]
pub struct LastEvaluation {
    /// The joints evaluated; `None` before the first evaluation.
    q: Option<[f64; MAX_JOINTS]>,
    tool: Frame,
    axes: Axes,
}

impl LastEvaluation {
    /// The tool pose at `q` on `chain`, evaluated unless `q` is the joints evaluated last; the
    /// joint axes are then [`axes`](Self::axes).
    pub(super) fn at(&mut self, chain: &Chain, q: &[f64; MAX_JOINTS]) -> Frame {
        let same = self
            .q
            .as_ref()
            .is_some_and(|last| last.iter().zip(q).all(|(a, b)| a.to_bits() == b.to_bits()));
        if !same {
            self.tool = chain.tool_and_axes(q, &mut self.axes);
            self.q = Some(*q);
        }
        self.tool
    }

    /// The joint axes of the last evaluation.
    pub(super) fn axes(&self) -> &Axes {
        &self.axes
    }
}
