//! The geometric Jacobian and the damped least-squares solve on it.

use nalgebra::{Cholesky, Matrix6, SMatrix, SVector, Vector6};

use crate::MAX_JOINTS;

/// A 6×[`MAX_JOINTS`] geometric Jacobian in base coordinates, reference point at the tool
/// origin. Column j maps joint j's rate to the tool twist `[vx, vy, vz, wx, wy, wz]`; the
/// columns past the chain's last joint are zero.
pub type Jacobian = SMatrix<f64, 6, MAX_JOINTS>;

/// Joint-space vectors of the solvers (entries past the last joint are zero).
pub(super) type JointVector = SVector<f64, MAX_JOINTS>;

/// Damped least squares `Δq = Jᵀ (J Jᵀ + λI)⁻¹ e`, which equals `(JᵀJ + λI)⁻¹ Jᵀ e` but is
/// always a 6×6 solve, whatever the joint count. The columns of `locked` joints count as zero,
/// so their entries of `Δq` are zero, and so do the columns from `n` on (joints the chain does
/// not have), which are skipped. `None` if the system is not positive definite (λ ≤ 0 or a
/// non-finite Jacobian).
pub(super) fn damped_least_squares(
    j: &Jacobian,
    n: usize,
    e: &Vector6<f64>,
    lambda: f64,
    locked: &[bool; MAX_JOINTS],
) -> Option<JointVector> {
    // Only the lower triangle is built: the rank-one updates and the Cholesky read no more.
    let mut a = Matrix6::from_diagonal_element(lambda);
    let columns = j.column_iter().zip(locked).take(n);
    for (column, _) in columns.filter(|(_, l)| !**l) {
        a.syger(1.0, &column, &column, 1.0);
    }
    let y = Cholesky::new(a)?.solve(e);
    let mut dq = j.tr_mul(&y);
    for (d, _) in dq.iter_mut().zip(locked).filter(|(_, l)| **l) {
        *d = 0.0;
    }
    Some(dq)
}
