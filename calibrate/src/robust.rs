//! Robustness to a bad line: iterative outlier rejection at k·σ.
//!
//! Least squares lets one mistyped coordinate pull every parameter. So after each fit, the pose
//! with the largest residual is set aside if its residual (a distance, weighted like the fit) is
//! beyond [`K`] times a robust noise estimate σ — the median residual converted to a
//! per-coordinate σ, never below the stated instrument noise nor [`SIGMA_FLOOR`] — and the fit
//! is repeated, until no pose is beyond. Then poses set aside that the final fit explains after
//! all are taken back once and fitted with the rest. At most [`MAX_REJECTED`] of the poses are
//! set aside: more than that is not a bad line but a model or data set that does not fit.

use crate::fit::{self, Fit, FitError, Measurement};
use crate::instrument::median;
use crate::model::{Geometry, Param};

/// The rejection threshold in robust σ. A per-pose distance beyond 5σ of 3-D Gaussian noise
/// has probability 1.5e-5 (χ² with 3 degrees of freedom beyond 25).
pub const K: f64 = 5.0;
/// The median of χ² with 3 degrees of freedom: median(distance²) / this estimates σ².
const MEDIAN_CHI2_3: f64 = 2.365_973_884_375_338;
/// Smallest σ the threshold assumes (m): noise-free data reject nothing.
pub const SIGMA_FLOOR: f64 = 1e-6;
/// Largest fraction of the poses that may be set aside.
pub const MAX_REJECTED: f64 = 0.1;

/// A pose set aside.
#[derive(Clone, Debug, PartialEq)]
pub struct Rejected {
    /// Its index in the measurements.
    pub index: usize,
    /// How reports name it (its line).
    pub name: String,
    /// Its residual against the final fit (m, weighted like the fit).
    pub residual: f64,
}

/// A fit without its outliers.
#[derive(Clone, Debug)]
pub struct RobustFit {
    /// The fit of the poses kept.
    pub fit: Fit,
    /// Indices of the poses kept.
    pub kept: Vec<usize>,
    /// The poses set aside, largest residual first.
    pub rejected: Vec<Rejected>,
    /// The threshold of the final fit (m): K times its robust σ.
    pub threshold: f64,
    /// True if more poses lie beyond the threshold than may be set aside.
    pub too_many: bool,
}

/// Fits `params` of `start` to `measurements` without the poses `suspect` first, setting aside
/// outliers and taking back the suspects the fit explains (see the module). `noise` is the
/// instrument's stated noise per coordinate (m), if any.
pub fn fit(
    start: &Geometry,
    params: &[Param],
    measurements: &[Measurement],
    suspect: &[usize],
    noise: Option<f64>,
) -> Result<RobustFit, FitError> {
    let n = measurements.len();
    let cap = (n as f64 * MAX_REJECTED).floor() as usize;
    // Never more set aside than this (gross errors beyond the cap stay out, and are counted).
    let limit = cap.max(suspect.len());
    let is_out = |out: &[bool], k: usize| out.get(k).copied().unwrap_or(false);
    let mut out: Vec<bool> = (0..n).map(|k| suspect.contains(&k)).collect();
    let mut geometry = start.clone();
    let mut took_back = false;
    // A pass sets one pose aside or takes poses back (once), so this many passes suffice.
    let passes = 2 * limit + 2;
    for pass in 1..=passes {
        let kept: Vec<usize> = (0..n).filter(|k| !is_out(&out, *k)).collect();
        let subset: Vec<Measurement> = kept
            .iter()
            .filter_map(|k| measurements.get(*k).cloned())
            .collect();
        let fitted = fit::fit(&geometry, params, &subset)?;
        geometry = fitted.geometry.clone();
        let residuals: Vec<f64> = measurements
            .iter()
            .map(|m| (m.position - geometry.position(&m.q)).norm() * m.weight.sqrt())
            .collect();
        let squares: Vec<f64> = kept
            .iter()
            .filter_map(|k| residuals.get(*k).map(|r| r * r))
            .collect();
        let sigma = (median(&squares) / MEDIAN_CHI2_3)
            .sqrt()
            .max(noise.unwrap_or(0.0))
            .max(SIGMA_FLOOR);
        let threshold = K * sigma;
        let worst = kept
            .iter()
            .filter_map(|k| residuals.get(*k).map(|r| (*k, *r)))
            .filter(|(_, r)| *r > threshold)
            .max_by(|a, b| a.1.total_cmp(&b.1));
        let out_count = out.iter().filter(|o| **o).count();
        let last = pass == passes;
        if let Some((k, _)) = worst
            && out_count < limit
            && !last
        {
            if let Some(o) = out.get_mut(k) {
                *o = true;
            }
            continue;
        }
        let back: Vec<usize> = (0..n)
            .filter(|k| is_out(&out, *k))
            .filter(|k| residuals.get(*k).is_some_and(|r| *r <= threshold))
            .collect();
        if !took_back && !back.is_empty() && !last {
            took_back = true;
            for k in back {
                if let Some(o) = out.get_mut(k) {
                    *o = false;
                }
            }
            continue;
        }
        let mut rejected: Vec<Rejected> = (0..n)
            .filter(|k| is_out(&out, *k))
            .map(|index| Rejected {
                index,
                name: measurements
                    .get(index)
                    .map_or_else(String::new, |m| m.name(index)),
                residual: residuals.get(index).copied().unwrap_or(0.0),
            })
            .collect();
        rejected.sort_by(|a, b| b.residual.total_cmp(&a.residual));
        return Ok(RobustFit {
            fit: fitted,
            kept,
            too_many: worst.is_some() || rejected.len() > cap,
            rejected,
            threshold,
        });
    }
    Err(FitError::NoMeasurements)
}
