//! Joint rates for a twist with the damping only along the smallest singular direction.
//!
//! Uniform damping (`Jᵀ(JJᵀ + λ²I)⁻¹`, what `Chain::joint_rates` does) also bends the
//! directions that are merely small: with λ = 0.05 a singular value of 0.19 loses 6.5 % of its
//! gain, and the tool leaves its line. Here `λ²` is added along the estimated smallest
//! direction `u` only, `Jᵀ(JJᵀ + λ² u uᵀ + λ_floor² I)⁻¹`, so every other direction is tracked
//! exactly; the small uniform floor keeps the system positive definite while `u` is still
//! being refined.

use nalgebra::{Cholesky, Matrix6, SVector, Vector6};

use super::damping::SingularDirection;
use crate::MAX_JOINTS;
use crate::kinematics::{Jacobian, Joints};
use crate::math::Twist;

/// The uniform floor, as a share of the damping along `u`.
const FLOOR_SHARE: f64 = 0.1;

/// `q̇ = z + Jᵀ(JJᵀ + λ² u uᵀ + (0.1 λ)² I)⁻¹ (ξ − J z)` for a chain of `n` joints, given
/// `outer` = `JJᵀ` (`z`: the null-space preference, zero for none). With fewer than six joints `JJᵀ` is singular and
/// the damping is full (`damping::smallest_singular_value`): the floor keeps the solve
/// positive definite, a least-squares answer. `None` if the system cannot be solved.
pub fn selectively_damped_rates(
    j: &Jacobian,
    outer: &Matrix6<f64>,
    n: usize,
    twist: &Twist,
    damping: f64,
    direction: &SingularDirection,
    preference: &Joints,
) -> Option<Joints> {
    let mut z = SVector::<f64, MAX_JOINTS>::zeros();
    for (zi, p) in z.iter_mut().zip(preference.iter()).take(n) {
        *zi = *p;
    }
    let u = direction.unit_6()?;
    let lambda2 = damping * damping;
    let floor = FLOOR_SHARE * FLOOR_SHARE * lambda2;
    let a: Matrix6<f64> =
        outer + u * u.transpose() * lambda2 + Matrix6::from_diagonal_element(floor);
    let residual: Vector6<f64> = twist - j * z;
    let y = Cholesky::new(a)?.solve(&residual);
    let dq = j.tr_mul(&y) + z;
    let mut rates = Joints::zeros(n);
    for (r, d) in rates.iter_mut().zip(dq.iter()) {
        *r = *d;
    }
    rates.is_finite().then_some(rates)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_singular_direction_is_damped() {
        // Singular values 1, 1, 1, 1, 0.2 and 0.01 (axis 6).
        let mut j = Jacobian::zeros();
        for (i, s) in [1.0, 1.0, 1.0, 1.0, 0.2, 0.01].into_iter().enumerate() {
            j[(i, i)] = s;
        }
        let mut direction = SingularDirection::default();
        let outer = j * j.transpose();
        for _ in 0..3 {
            super::super::damping::smallest_singular_value(&outer, 6, &mut direction);
        }
        let twist = Twist::new(0.0, 0.0, 0.0, 0.0, 0.1, 0.1);
        let none = Joints::zeros(6);
        let q = selectively_damped_rates(&j, &outer, 6, &twist, 0.05, &direction, &none).unwrap();
        // Axis 5 (σ = 0.2) exact up to the floor: 0.1 / 0.2 · (1 − 1.6e-4).
        assert!((q[4] - 0.5).abs() < 1e-3, "{q:?}");
        // Axis 6 damped: σ / (σ² + λ²) · 0.1 ≈ 0.38 instead of 10.
        assert!(q[5] < 0.5 && q[5] > 0.3, "{q:?}");
        assert!(q[..4].iter().all(|v| v.abs() < 1e-12));
    }
}
