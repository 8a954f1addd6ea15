//! Damping of the pseudo-inverse that grows smoothly near a singularity (instead of stopping).

use nalgebra::{Cholesky, SMatrix, SVector};

use crate::MAX_JOINTS;
use crate::kinematics::Jacobian;

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
pub struct SingularDirection([f64; MAX_JOINTS]);

impl SingularDirection {
    /// The first six entries, normalised: the direction in twist space when the estimate
    /// runs on `J Jᵀ` (six joints or more); `None` if it has no length.
    pub fn unit_6(&self) -> Option<nalgebra::Vector6<f64>> {
        let [a, b, c, d, e, f, ..] = self.0;
        let u = nalgebra::Vector6::new(a, b, c, d, e, f);
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

/// The damping λ for the Jacobian `j` of an `n`-joint chain:
/// `λ = λ_max √(1 − (σ/ε)²)` below the threshold ε, 0 above it (continuous in σ, the smallest
/// singular value of the joints the chain has). A Jacobian whose singular values cannot be
/// estimated gets the full damping.
pub fn singularity_damping(j: &Jacobian, n: usize, direction: &mut SingularDirection) -> f64 {
    let sigma = smallest_singular_value(j, n, direction).unwrap_or(0.0);
    if sigma >= SINGULAR_THRESHOLD {
        return 0.0;
    }
    let ratio = sigma / SINGULAR_THRESHOLD;
    MAX_DAMPING * libm::sqrt(1.0 - ratio * ratio)
}

/// An estimate (from above) of the smallest of the `min(n, 6)` singular values of `j`, by
/// inverse iteration on `J Jᵀ` (six joints or more) or on `Jᵀ J` with ones for the joints the
/// chain does not have (fewer): bounded, a Cholesky factorisation and a few solves, no
/// eigen-solver. `None` if the matrix is not positive definite or not finite (σ ≈ 0).
pub fn smallest_singular_value(
    j: &Jacobian,
    n: usize,
    direction: &mut SingularDirection,
) -> Option<f64> {
    let eigenvalue = if n >= 6 {
        smallest_eigenvalue(j * j.transpose(), direction)
    } else {
        let unused = SVector::<f64, MAX_JOINTS>::from_fn(|i, _| f64::from(u8::from(i >= n)));
        smallest_eigenvalue(j.tr_mul(j) + SMatrix::from_diagonal(&unused), direction)
    }?;
    Some(libm::sqrt(eigenvalue.max(0.0)))
}

/// The Rayleigh quotient after [`ITERATIONS`] inverse-iteration steps on the symmetric `a`,
/// starting from (and updating) the first `D` entries of `direction`.
fn smallest_eigenvalue<const D: usize>(
    a: SMatrix<f64, D, D>,
    direction: &mut SingularDirection,
) -> Option<f64> {
    let mut x = SVector::<f64, D>::from_fn(|i, _| direction.0.get(i).copied().unwrap_or(1.0));
    let cholesky = Cholesky::new(a)?;
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
    let quotient = x.dot(&(a * x));
    quotient.is_finite().then_some(quotient)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn diagonal(s: f64) -> Jacobian {
        let mut j = Jacobian::zeros();
        for i in 0..6 {
            j[(i, i)] = if i == 4 { s } else { 1.0 };
        }
        j
    }

    fn damping(j: &Jacobian) -> f64 {
        singularity_damping(j, 6, &mut SingularDirection::default())
    }

    #[test]
    fn damping_is_zero_above_the_threshold_and_rises_smoothly_to_the_maximum() {
        assert_eq!(damping(&diagonal(0.5)), 0.0);
        assert_eq!(damping(&diagonal(SINGULAR_THRESHOLD)), 0.0);
        assert!((damping(&diagonal(0.0)) - MAX_DAMPING).abs() < 1e-12);
        let half = damping(&diagonal(0.5 * SINGULAR_THRESHOLD));
        assert!(
            (half - MAX_DAMPING * libm::sqrt(0.75)).abs() < 1e-9,
            "{half}"
        );
        // Continuous: no jump as σ crosses the threshold.
        let near = damping(&diagonal(SINGULAR_THRESHOLD * (1.0 - 1e-9)));
        assert!(near < 1e-3 * MAX_DAMPING, "{near}");
    }

    #[test]
    fn warm_starts_converge_on_a_well_separated_smallest_value() {
        let mut direction = SingularDirection::default();
        let sigma = smallest_singular_value(&diagonal(0.02), 6, &mut direction).unwrap();
        assert!((sigma - 0.02).abs() < 1e-9, "{sigma}");
        // The direction is kept: axis 5.
        assert!((direction.0[4].abs() - 1.0).abs() < 1e-9);
    }

    #[test]
    fn fewer_joints_skip_the_rows_they_cannot_move() {
        let mut j = Jacobian::zeros();
        j[(0, 0)] = 0.5;
        j[(1, 1)] = 3.0;
        let mut direction = SingularDirection::default();
        let sigma = smallest_singular_value(&j, 2, &mut direction).unwrap();
        assert!(sigma >= 0.5 && sigma - 0.5 < 1e-3, "from above: {sigma}");
        // The ticks that follow refine it (warm start).
        for _ in 0..4 {
            smallest_singular_value(&j, 2, &mut direction);
        }
        let sigma = smallest_singular_value(&j, 2, &mut direction).unwrap();
        assert!((sigma - 0.5).abs() < 1e-12, "{sigma}");
        assert_eq!(smallest_singular_value(&j, 6, &mut direction), None);
        let nan = Jacobian::from_element(f64::NAN);
        assert_eq!(damping(&nan), MAX_DAMPING);
    }
}
