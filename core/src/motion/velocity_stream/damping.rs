//! Damping of the pseudo-inverse that grows smoothly near a singularity (instead of stopping).

use nalgebra::{Cholesky, Matrix6};

/// Below this smallest singular value of the weighted Jacobian (linear rows × `LINEAR_WEIGHT`,
/// see the module) the damping starts to rise. The shipped arms show 0.5–0.7 in comfortable
/// poses.
pub const SINGULAR_THRESHOLD: f64 = 0.08;

/// The damping λ at the singularity itself (σ = 0). Joint rates stay below `|ξ| / (2λ)` along
/// the singular direction, whatever σ.
pub const MAX_DAMPING: f64 = 0.05;

/// Inverse-iteration steps per tick. Warm-started from the previous tick's vector, the
/// estimate follows the smallest singular direction as the arm moves; near a singularity,
/// where it matters, one step already gains the ratio of the two smallest singular values.
const ITERATIONS: usize = 4;

/// The estimate of the direction of the smallest singular value, kept across ticks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SingularDirection([f64; 6]);

impl SingularDirection {
    /// The direction, normalised; `None` if it has no length.
    pub fn unit_6(&self) -> Option<nalgebra::Vector6<f64>> {
        let u = nalgebra::Vector6::from(self.0);
        let norm = u.norm();
        (norm.is_finite() && norm > 0.0).then(|| u / norm)
    }
}

impl Default for SingularDirection {
    fn default() -> Self {
        // Not orthogonal to any axis: every direction has a share in it.
        Self(core::array::from_fn(|i| 1.0 + 0.1 * i as f64))
    }
}

/// The damping λ for the Jacobian `J` of an `n`-joint chain, given `outer` = `J Jᵀ`:
/// `λ = λ_max √(1 − (σ/ε)²)` below the threshold ε, 0 above it (continuous in σ, the smallest
/// singular value of the joints the chain has). A Jacobian whose singular values cannot be
/// estimated gets the full damping.
pub fn singularity_damping(
    outer: &Matrix6<f64>,
    n: usize,
    direction: &mut SingularDirection,
) -> f64 {
    let sigma = smallest_singular_value(outer, n, direction).unwrap_or(0.0);
    if sigma >= SINGULAR_THRESHOLD {
        return 0.0;
    }
    let ratio = sigma / SINGULAR_THRESHOLD;
    MAX_DAMPING * crate::math::sqrt(1.0 - ratio * ratio)
}

/// An estimate (from above) of the smallest singular value of `J` (six joints or more), by
/// inverse iteration on `outer` = `J Jᵀ`: bounded, a Cholesky factorisation and a few solves, no
/// eigen-solver. A chain of fewer than six joints cannot produce every twist: 0. `None` if
/// `J Jᵀ` is not positive definite or not finite (σ ≈ 0).
pub fn smallest_singular_value(
    outer: &Matrix6<f64>,
    n: usize,
    direction: &mut SingularDirection,
) -> Option<f64> {
    if n < 6 {
        return Some(0.0);
    }
    let mut x = direction.unit_6()?;
    let cholesky = Cholesky::new(*outer)?;
    for _ in 0..ITERATIONS {
        let y = cholesky.solve(&x);
        let norm = y.norm();
        if !(norm.is_finite() && norm > 0.0) {
            return None;
        }
        x = y / norm;
    }
    for (d, v) in direction.0.iter_mut().zip(x.iter()) {
        *d = *v;
    }
    let quotient = x.dot(&(outer * x));
    quotient
        .is_finite()
        .then(|| crate::math::sqrt(quotient.max(0.0)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::Jacobian;

    fn outer(j: &Jacobian) -> Matrix6<f64> {
        j * j.transpose()
    }

    fn diagonal(s: f64) -> Jacobian {
        let mut j = Jacobian::zeros();
        for i in 0..6 {
            j[(i, i)] = if i == 4 { s } else { 1.0 };
        }
        j
    }

    fn damping(j: &Jacobian) -> f64 {
        singularity_damping(&outer(j), 6, &mut SingularDirection::default())
    }

    #[test]
    fn damping_is_zero_above_the_threshold_and_rises_smoothly_to_the_maximum() {
        assert_eq!(damping(&diagonal(0.5)), 0.0);
        assert_eq!(damping(&diagonal(SINGULAR_THRESHOLD)), 0.0);
        assert!((damping(&diagonal(0.0)) - MAX_DAMPING).abs() < 1e-12);
        let half = damping(&diagonal(0.5 * SINGULAR_THRESHOLD));
        assert!(
            (half - MAX_DAMPING * crate::math::sqrt(0.75)).abs() < 1e-9,
            "{half}"
        );
        // Continuous: no jump as σ crosses the threshold.
        let near = damping(&diagonal(SINGULAR_THRESHOLD * (1.0 - 1e-9)));
        assert!(near < 1e-3 * MAX_DAMPING, "{near}");
    }

    #[test]
    fn warm_starts_converge_on_a_well_separated_smallest_value() {
        let mut direction = SingularDirection::default();
        let sigma = smallest_singular_value(&outer(&diagonal(0.02)), 6, &mut direction).unwrap();
        assert!((sigma - 0.02).abs() < 1e-9, "{sigma}");
        // The direction is kept: axis 5.
        assert!((direction.0[4].abs() - 1.0).abs() < 1e-9);
    }

    #[test]
    fn fewer_joints_are_singular_and_warm_starts_refine_the_estimate() {
        let mut j = diagonal(1.0);
        j[(5, 5)] = 0.5;
        let mut direction = SingularDirection::default();
        assert_eq!(
            smallest_singular_value(&outer(&j), 5, &mut direction),
            Some(0.0)
        );
        let sigma = smallest_singular_value(&outer(&j), 6, &mut direction).unwrap();
        assert!(sigma >= 0.5 && sigma - 0.5 < 1e-3, "from above: {sigma}");
        // The ticks that follow refine it (warm start).
        for _ in 0..4 {
            smallest_singular_value(&outer(&j), 6, &mut direction);
        }
        let sigma = smallest_singular_value(&outer(&j), 6, &mut direction).unwrap();
        assert!((sigma - 0.5).abs() < 1e-12, "{sigma}");
        let nan = Jacobian::from_element(f64::NAN);
        assert_eq!(damping(&nan), MAX_DAMPING);
    }
}
