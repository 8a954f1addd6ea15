//! Levenberg–Marquardt identification, parameter uncertainties and residual statistics.

use nalgebra::{DMatrix, DVector, Vector3};

use crate::identify::jacobian;
use crate::model::{Geometry, Param};

/// Iteration limit of one fit; a well-posed calibration converges in well under ten.
const MAX_ITERATIONS: usize = 100;
/// Stop when a step lowers the cost by less than this fraction.
const TOLERANCE: f64 = 1e-14;

/// One measured pose: the joint values and the tool position an instrument measured.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    /// Joint values (rad or m), one per joint.
    pub q: Vec<f64>,
    /// Measured tool position in the world (instrument) frame (m).
    pub position: Vector3<f64>,
    /// Relative weight of this pose (1 = normal); e.g. the inverse variance of the instrument.
    pub weight: f64,
    /// Its line in the file it was read from (1-based; 0 if it was not read from a file).
    pub line: usize,
}

impl Measurement {
    /// How reports name it: its line, or its position in the list (1-based).
    pub fn name(&self, index: usize) -> String {
        if self.line > 0 {
            format!("line {}", self.line)
        } else {
            format!("measurement {}", index + 1)
        }
    }
}

/// Distances between measured and predicted tool positions.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Residuals {
    /// Number of poses.
    pub count: usize,
    /// Mean distance (m).
    pub mean: f64,
    /// Root-mean-square distance (m).
    pub rms: f64,
    /// Largest distance (m).
    pub max: f64,
    /// Sample standard deviation of the distances (m), as the seed reported it.
    pub std_dev: f64,
}

impl Residuals {
    /// The statistics of `geometry`'s errors at `measurements`.
    pub fn of(geometry: &Geometry, measurements: &[Measurement]) -> Self {
        let distances: Vec<f64> = measurements
            .iter()
            .map(|m| (m.position - geometry.position(&m.q)).norm())
            .collect();
        Self::from_distances(&distances)
    }

    /// The statistics of a list of distances.
    pub fn from_distances(d: &[f64]) -> Self {
        let n = d.len();
        if n == 0 {
            return Self::default();
        }
        let mean = d.iter().sum::<f64>() / n as f64;
        let rms = (d.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
        let max = d.iter().copied().fold(0.0, f64::max);
        let var = d.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n.max(2) - 1) as f64;
        Self {
            count: n,
            mean,
            rms,
            max,
            std_dev: var.sqrt(),
        }
    }
}

/// The result of a fit.
#[derive(Clone, Debug)]
pub struct Fit {
    /// The fitted geometry (unfitted parameters as they started).
    pub geometry: Geometry,
    /// The fitted parameters.
    pub params: Vec<Param>,
    /// Their standard deviations (same units), from the covariance `s² (JᵀWJ)⁻¹` with `s²`
    /// the a-posteriori variance of unit weight.
    pub std_dev: Vec<f64>,
    /// That covariance (rows and columns in the order of `params`).
    pub covariance: DMatrix<f64>,
    /// `s`: the RMS weighted residual per coordinate (m), an estimate of the instrument noise.
    pub sigma: f64,
    /// Iterations used.
    pub iterations: usize,
}

/// Why a fit failed.
#[derive(Clone, Debug, PartialEq)]
pub enum FitError {
    /// No measurements at all.
    NoMeasurements,
    /// Fewer residuals (3 per pose) than parameters plus one.
    TooFewPoses {
        /// Poses given.
        poses: usize,
        /// Parameters to fit.
        params: usize,
    },
    /// A measurement's joint count differs from the robot's.
    WrongJointCount {
        /// Index of the measurement (0-based).
        pose: usize,
    },
    /// The normal equations are singular: the parameters are not identifiable from these poses.
    Singular,
    /// The measured positions do not fix the instrument's orientation (fewer than three poses,
    /// or all on one line).
    Unregistrable,
}

impl std::fmt::Display for FitError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NoMeasurements => f.write_str("no measurements"),
            Self::TooFewPoses { poses, params } => write!(
                f,
                "{poses} poses give {} residuals; {params} parameters need more",
                3 * poses
            ),
            Self::WrongJointCount { pose } => {
                write!(f, "measurement {} has the wrong number of joints", pose + 1)
            }
            Self::Singular => f.write_str("the parameters are not identifiable from these poses"),
            Self::Unregistrable => f.write_str(
                "the measured positions do not fix the instrument's frame (fewer than three, or \
                 all on one line)",
            ),
        }
    }
}

impl std::error::Error for FitError {}

/// Weighted residual vector `√w · (measured − predicted)`.
fn residual(geometry: &Geometry, measurements: &[Measurement]) -> DVector<f64> {
    let mut r = DVector::zeros(3 * measurements.len());
    for (k, m) in measurements.iter().enumerate() {
        let e = (m.position - geometry.position(&m.q)) * m.weight.sqrt();
        r.fixed_rows_mut::<3>(3 * k).copy_from(&e);
    }
    r
}

/// The identification Jacobian with rows weighted by `√w`.
fn weighted_jacobian(
    geometry: &Geometry,
    params: &[Param],
    measurements: &[Measurement],
) -> DMatrix<f64> {
    let poses: Vec<Vec<f64>> = measurements.iter().map(|m| m.q.clone()).collect();
    let mut j = jacobian(geometry, params, &poses);
    for (k, m) in measurements.iter().enumerate() {
        j.rows_mut(3 * k, 3).scale_mut(m.weight.sqrt());
    }
    j
}

/// Fits `params` of `start` to `measurements` by Levenberg–Marquardt (Marquardt's diagonal
/// scaling, so that metres and radians need no common unit).
pub fn fit(
    start: &Geometry,
    params: &[Param],
    measurements: &[Measurement],
) -> Result<Fit, FitError> {
    let dof = start.dof();
    if let Some(pose) = measurements.iter().position(|m| m.q.len() != dof) {
        return Err(FitError::WrongJointCount { pose });
    }
    let rows = 3 * measurements.len();
    if rows <= params.len() {
        return Err(FitError::TooFewPoses {
            poses: measurements.len(),
            params: params.len(),
        });
    }
    let mut geometry = start.clone();
    let mut r = residual(&geometry, measurements);
    let mut cost = r.norm_squared();
    let mut lambda = 1e-3;
    let mut iterations = 0;
    while iterations < MAX_ITERATIONS {
        iterations += 1;
        let j = weighted_jacobian(&geometry, params, measurements);
        let jtj = j.transpose() * &j;
        let jtr = j.transpose() * &r;
        let mut improved = false;
        // Raise λ until a step lowers the cost (bounded: λ grows ×10 per try).
        for _ in 0..20 {
            let damping = jtj.diagonal().map(|v| lambda * v.max(1e-12));
            let a = &jtj + DMatrix::from_diagonal(&damping);
            let Some(step) = a.cholesky().map(|c| c.solve(&jtr)) else {
                lambda *= 10.0;
                continue;
            };
            let values = DVector::from_vec(geometry.values(params)) + step;
            let trial = geometry.with(params, values.as_slice());
            let trial_r = residual(&trial, measurements);
            let trial_cost = trial_r.norm_squared();
            if trial_cost < cost {
                let gain = (cost - trial_cost) / cost.max(f64::MIN_POSITIVE);
                geometry = trial;
                r = trial_r;
                cost = trial_cost;
                lambda = (lambda / 10.0).max(1e-12);
                improved = gain > TOLERANCE;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    let j = weighted_jacobian(&geometry, params, measurements);
    let information = j.transpose() * &j;
    let variance = cost / (rows - params.len()) as f64;
    let covariance = information.try_inverse().ok_or(FitError::Singular)? * variance;
    let std_dev = covariance
        .diagonal()
        .iter()
        .map(|c| c.max(0.0).sqrt())
        .collect();
    Ok(Fit {
        geometry,
        params: params.to_vec(),
        std_dev,
        covariance,
        sigma: variance.sqrt(),
        iterations,
    })
}

/// k-fold cross-validation: each pose's error when the fit left it out (pose i is in fold
/// i mod k). Returns the held-out residual statistics.
pub fn cross_validate(
    start: &Geometry,
    params: &[Param],
    measurements: &[Measurement],
    folds: usize,
) -> Result<Residuals, FitError> {
    let folds = folds.max(2);
    let mut distances = Vec::with_capacity(measurements.len());
    for fold in 0..folds {
        let (test, train): (Vec<_>, Vec<_>) = measurements
            .iter()
            .enumerate()
            .partition(|(i, _)| i % folds == fold);
        let train: Vec<Measurement> = train.into_iter().map(|(_, m)| m.clone()).collect();
        let fitted = fit(start, params, &train)?;
        distances.extend(
            test.into_iter()
                .map(|(_, m)| (m.position - fitted.geometry.position(&m.q)).norm()),
        );
    }
    Ok(Residuals::from_distances(&distances))
}
