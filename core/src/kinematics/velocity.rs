//! Inverse velocity kinematics: a tool twist to joint rates.

use super::chain::{Chain, KinematicsError};
use super::joints::Joints;
use super::linalg;
use crate::MAX_JOINTS;
use crate::math::Twist;

impl Chain {
    /// Joint rates that produce the tool `twist` (base frame, tool origin):
    /// `q̇ = z + J⁺(ξ − J z)` with the damped pseudo-inverse `J⁺ = (JᵀJ + λ²I)⁻¹Jᵀ`.
    ///
    /// `damping` (λ) bounds the rates near a singularity (0 gives the plain least-squares
    /// solution away from singularities). `null_space` is a joint-rate preference `z` — for a
    /// redundant arm, for example a pull towards mid-range — of which only the part that does not
    /// disturb the tool motion is kept; pass `None` for the minimum-norm solution.
    pub fn joint_rates(
        &self,
        q: &[f64],
        twist: &Twist,
        damping: f64,
        null_space: Option<&[f64]>,
    ) -> Result<Joints, KinematicsError> {
        let j = self.jacobian(q)?;
        let n = self.dof();
        let z = match null_space {
            Some(z) => self.check(z)?,
            None => Joints::zeros(n),
        };
        if !twist.linear.is_finite() || !twist.angular.is_finite() || !damping.is_finite() {
            return Err(KinematicsError::NonFiniteJoints);
        }
        let moved = j.twist(&z).to_array();
        let mut residual = twist.to_array();
        for (r, m) in residual.iter_mut().zip(moved) {
            *r -= m;
        }
        let mut a = [[0.0; MAX_JOINTS]; MAX_JOINTS];
        j.damped_gram_into((damping * damping).max(1e-12), &[false; MAX_JOINTS], &mut a);
        let mut dq = j.transpose_mul(&residual);
        if !linalg::cholesky_solve(&mut a, &mut dq, n) {
            dq = [0.0; MAX_JOINTS];
        }
        let mut rates = z;
        for (r, d) in rates.iter_mut().zip(dq) {
            *r += d;
        }
        Ok(rates)
    }
}
