//! Inverse velocity kinematics: a tool twist to joint rates.

use super::chain::{Chain, KinematicsError};
use super::jacobian::{JointVector, damped_least_squares};
use crate::MAX_JOINTS;
use crate::math::Joints;
use crate::math::Twist;

impl Chain {
    /// Joint rates that produce the tool `twist` (base frame, tool origin):
    /// `q̇ = z + J⁺(ξ − J z)` with the damped pseudo-inverse `J⁺ = Jᵀ(JJᵀ + λ²I)⁻¹`.
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
        if !twist.iter().all(|v| v.is_finite()) || !damping.is_finite() {
            return Err(KinematicsError::NonFiniteJoints);
        }
        let residual = twist - j * JointVector::from(*z.as_array());
        let lambda = (damping * damping).max(1e-12);
        let dq = damped_least_squares(&j, n, &residual, lambda, &[false; MAX_JOINTS])
            .unwrap_or_else(JointVector::zeros);
        let mut rates = z;
        for (r, d) in rates.iter_mut().zip(dq.iter()) {
            *r += d;
        }
        Ok(rates)
    }
}
