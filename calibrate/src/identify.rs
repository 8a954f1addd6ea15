//! Identifiability: which parameters the measured poses can determine.
//!
//! The identification Jacobian `J = ∂(tool positions)/∂(parameters)` at the poses decides it. A
//! parameter whose column is (numerically) a combination of the columns kept before it — for
//! example the base yaw against the first joint's offset, or `d` of two parallel axes — cannot be
//! identified: it is fixed at its nominal value and named. Angles are scaled by the poses' mean
//! reach, so that singular values and the condition number compare metres with metres.

use nalgebra::{DMatrix, DVector};

use crate::model::{Geometry, Param};

/// Central-difference step (m or rad); its truncation error (~h²) is far below metrology noise.
const STEP: f64 = 1e-6;
/// A column whose part orthogonal to the kept columns is smaller than this fraction of its own
/// length is dependent on them. Exact redundancies give ~1e-10 (the differentiation error).
const DEPENDENT: f64 = 1e-6;

/// The identification Jacobian (3 rows per pose, one column per parameter), in SI units.
pub fn jacobian(geometry: &Geometry, params: &[Param], poses: &[Vec<f64>]) -> DMatrix<f64> {
    let mut j = DMatrix::zeros(3 * poses.len(), params.len());
    for (col, &p) in params.iter().enumerate() {
        let value = geometry.get(p);
        let mut plus = geometry.clone();
        plus.set(p, value + STEP);
        let mut minus = geometry.clone();
        minus.set(p, value - STEP);
        for (k, q) in poses.iter().enumerate() {
            let dp = (plus.position(q) - minus.position(q)) / (2.0 * STEP);
            j.fixed_view_mut::<3, 1>(3 * k, col).copy_from(&dp);
        }
    }
    j
}

/// The characteristic length that makes angles comparable with lengths: the RMS distance of
/// the tool from the robot's world origin over the poses (at least 0.1 m).
pub fn reach(geometry: &Geometry, poses: &[Vec<f64>]) -> f64 {
    let sum: f64 = poses
        .iter()
        .map(|q| geometry.robot_position(q).norm_squared())
        .sum();
    (sum / poses.len().max(1) as f64).sqrt().max(0.1)
}

/// `J` with angle columns divided by `reach`: columns in metres per (scaled) metre.
pub fn scaled(j: &DMatrix<f64>, params: &[Param], reach: f64) -> DMatrix<f64> {
    let mut s = j.clone();
    for (mut col, p) in s.column_iter_mut().zip(params) {
        if p.is_angle() {
            col /= reach;
        }
    }
    s
}

/// The outcome of the identifiability analysis.
#[derive(Clone, Debug)]
pub struct Identifiability {
    /// The parameters that will be fitted, in candidate order.
    pub identified: Vec<Param>,
    /// The parameters the poses cannot determine; they keep their nominal values.
    pub unidentifiable: Vec<Param>,
    /// Singular values of the scaled Jacobian of all candidates, largest first: as many are
    /// (numerically) zero as there are unidentifiable parameters.
    pub singular_values: Vec<f64>,
    /// Condition number of the scaled Jacobian of the identified parameters.
    pub condition: f64,
    /// Observability index O1 = (σ₁…σ_m)^(1/m) / √poses of that Jacobian (m per scaled unit).
    pub observability: f64,
    /// The reach used to scale angles (m).
    pub reach: f64,
}

/// Analyses the candidates `params` at `poses`: keeps, in order, each parameter whose Jacobian
/// column is not a combination of those kept before it (a pivoted Gram–Schmidt in a fixed
/// priority order), then reports the SVD figures.
pub fn analyse(geometry: &Geometry, params: &[Param], poses: &[Vec<f64>]) -> Identifiability {
    let reach = reach(geometry, poses);
    let j = scaled(&jacobian(geometry, params, poses), params, reach);
    let largest = j.column_iter().map(|c| c.norm()).fold(0.0, f64::max);
    let mut basis: Vec<DVector<f64>> = Vec::new();
    let mut identified = Vec::new();
    let mut unidentifiable = Vec::new();
    for (col, &p) in j.column_iter().zip(params) {
        let norm = col.norm();
        let mut r: DVector<f64> = col.into_owned();
        // Two passes of classical Gram–Schmidt: orthogonal to working precision.
        for _ in 0..2 {
            for b in &basis {
                let along = b.dot(&r);
                r.axpy(-along, b, 1.0);
            }
        }
        let rest = r.norm();
        if norm > DEPENDENT * largest && rest > DEPENDENT * norm {
            basis.push(r / rest);
            identified.push(p);
        } else {
            unidentifiable.push(p);
        }
    }
    let singular_values = singular_values(&j);
    let kept: Vec<usize> = params
        .iter()
        .enumerate()
        .filter(|(_, p)| identified.contains(p))
        .map(|(k, _)| k)
        .collect();
    let reduced = j.select_columns(&kept);
    let (condition, observability) = conditioning(&reduced, poses.len());
    Identifiability {
        identified,
        unidentifiable,
        singular_values,
        condition,
        observability,
        reach,
    }
}

/// Singular values, largest first (none for an empty matrix).
pub fn singular_values(j: &DMatrix<f64>) -> Vec<f64> {
    if j.is_empty() {
        return Vec::new();
    }
    let mut s: Vec<f64> = j.singular_values().iter().copied().collect();
    s.sort_by(|a, b| b.total_cmp(a));
    s
}

/// Condition number σ_max/σ_min and observability index O1 of a scaled Jacobian.
pub fn conditioning(j: &DMatrix<f64>, poses: usize) -> (f64, f64) {
    let s = singular_values(j);
    let (Some(max), Some(min)) = (s.first(), s.last()) else {
        return (f64::INFINITY, 0.0);
    };
    let log_mean = s.iter().map(|v| v.max(f64::MIN_POSITIVE).ln()).sum::<f64>() / s.len() as f64;
    (max / min, log_mean.exp() / (poses.max(1) as f64).sqrt())
}
