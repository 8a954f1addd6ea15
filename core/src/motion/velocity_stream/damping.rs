//! Damping of the pseudo-inverse that grows smoothly near a singularity (instead of stopping).

use nalgebra::{Matrix6, SymmetricEigen};

use crate::kinematics::Jacobian;

/// Below this smallest singular value of the Jacobian (m, or rad for the angular rows: the
/// rows are mixed, as in the seed's IK) the damping starts to rise. About a tenth of what a
/// 1 m arm shows away from its singularities.
pub const SINGULAR_THRESHOLD: f64 = 0.08;

/// The damping λ at the singularity itself (σ = 0). Joint rates stay below `|ξ| / (2λ)` along
/// the singular direction, whatever σ.
pub const MAX_DAMPING: f64 = 0.05;

/// Sweeps of the symmetric eigen-solver: a 6×6 converges in far fewer; the bound keeps the
/// tick bounded for any input.
const EIGEN_ITERATIONS: usize = 64;

/// The damping λ for the Jacobian `j` of an `n`-joint chain:
/// `λ² = λ_max² (1 − (σ/ε)²)` below the threshold ε, 0 above it (Nakamura and Hanafusa's
/// scheme, continuous in σ, the smallest singular value of the joints the chain has). A
/// Jacobian whose singular values cannot be computed gets the full damping.
pub fn singularity_damping(j: &Jacobian, n: usize) -> f64 {
    let sigma = smallest_singular_value(j, n).unwrap_or(0.0);
    if sigma >= SINGULAR_THRESHOLD {
        return 0.0;
    }
    let ratio = sigma / SINGULAR_THRESHOLD;
    MAX_DAMPING * libm::sqrt(1.0 - ratio * ratio)
}

/// The smallest of the `min(n, 6)` singular values of `j` (the square roots of the
/// eigenvalues of `J Jᵀ`, of which `6 − n` are zero for a chain of fewer than six joints).
pub fn smallest_singular_value(j: &Jacobian, n: usize) -> Option<f64> {
    let outer: Matrix6<f64> = j * j.transpose();
    let eigen = SymmetricEigen::try_new(outer, f64::EPSILON, EIGEN_ITERATIONS)?;
    let mut values: [f64; 6] = eigen.eigenvalues.into();
    values.sort_unstable_by(f64::total_cmp);
    let rank = n.min(6);
    let smallest = values.get(6 - rank).copied()?;
    smallest.is_finite().then(|| libm::sqrt(smallest.max(0.0)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn damping_is_zero_above_the_threshold_and_rises_smoothly_to_the_maximum() {
        let diagonal = |s: f64| {
            let mut j = Jacobian::zeros();
            for i in 0..6 {
                j[(i, i)] = if i == 4 { s } else { 1.0 };
            }
            j
        };
        assert_eq!(singularity_damping(&diagonal(0.5), 6), 0.0);
        assert_eq!(singularity_damping(&diagonal(SINGULAR_THRESHOLD), 6), 0.0);
        assert!((singularity_damping(&diagonal(0.0), 6) - MAX_DAMPING).abs() < 1e-12);
        let half = singularity_damping(&diagonal(0.5 * SINGULAR_THRESHOLD), 6);
        assert!(
            (half - MAX_DAMPING * libm::sqrt(0.75)).abs() < 1e-9,
            "{half}"
        );
        // Continuous: no jump as σ crosses the threshold.
        let near = singularity_damping(&diagonal(SINGULAR_THRESHOLD * (1.0 - 1e-9)), 6);
        assert!(near < 1e-3 * MAX_DAMPING, "{near}");
    }

    #[test]
    fn fewer_joints_skip_the_rows_they_cannot_move() {
        let mut j = Jacobian::zeros();
        j[(0, 0)] = 2.0;
        j[(1, 1)] = 3.0;
        assert_eq!(smallest_singular_value(&j, 2), Some(2.0));
        assert_eq!(smallest_singular_value(&j, 6), Some(0.0));
        let nan = Jacobian::from_element(f64::NAN);
        assert_eq!(singularity_damping(&nan, 6), MAX_DAMPING);
    }
}
