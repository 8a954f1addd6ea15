//! One calibration run: identifiability analysis, the fit, validation and the report.

use std::fmt::Write as _;

use armgate_core::config::RobotConfig;

use crate::fit::{self, Fit, FitError, Measurement, Residuals};
use crate::identify::{self, Identifiability};
use crate::model::{self, FitSet, Geometry};

/// Folds of the cross-validation run when no held-out poses are given.
pub const FOLDS: usize = 5;
/// Above this condition number the poses determine the parameters poorly: the fit may match
/// them and be wrong elsewhere (published guidance: ≲ 100).
pub const WELL_CONDITIONED: f64 = 100.0;

/// How the calibrated model was checked on poses it was not fitted to.
#[derive(Clone, Copy, Debug)]
pub enum Validation {
    /// Separately measured poses: errors of the nominal and of the calibrated model.
    HeldOut {
        /// Nominal model.
        before: Residuals,
        /// Calibrated model.
        after: Residuals,
    },
    /// k-fold cross-validation on the fitting poses: each pose predicted by a fit without it.
    CrossValidation {
        /// Number of folds.
        folds: usize,
        /// Errors of the left-out poses.
        after: Residuals,
    },
    /// No held-out poses, and too few poses to fit without a fold.
    Unavailable,
}

/// The outcome of a calibration.
#[derive(Clone, Debug)]
pub struct Calibration {
    /// The robot's geometry as its file states it.
    pub nominal: Geometry,
    /// Which parameters were fitted and which could not be.
    pub analysis: Identifiability,
    /// The fit.
    pub fit: Fit,
    /// Errors at the fitting poses, nominal model.
    pub before: Residuals,
    /// Errors at the fitting poses, calibrated model.
    pub after: Residuals,
    /// Errors on poses the fit did not see.
    pub validation: Validation,
}

/// Calibrates the parameters of `set` of `config` from `measurements`, checking the result on
/// `held_out` poses, or by cross-validation when there are none.
pub fn calibrate(
    config: &RobotConfig,
    measurements: &[Measurement],
    held_out: &[Measurement],
    set: FitSet,
) -> Result<Calibration, FitError> {
    let nominal = Geometry::new(config);
    if measurements.is_empty() {
        return Err(FitError::NoMeasurements);
    }
    if let Some(pose) = measurements
        .iter()
        .chain(held_out)
        .position(|m| m.q.len() != nominal.dof())
    {
        return Err(FitError::WrongJointCount { pose });
    }
    let poses: Vec<Vec<f64>> = measurements.iter().map(|m| m.q.clone()).collect();
    let analysis = identify::analyse(&nominal, &nominal.candidates(set), &poses);
    let fit = fit::fit(&nominal, &analysis.identified, measurements)?;
    let validation = if held_out.is_empty() {
        match fit::cross_validate(&nominal, &analysis.identified, measurements, FOLDS) {
            Ok(after) => Validation::CrossValidation {
                folds: FOLDS,
                after,
            },
            Err(_) => Validation::Unavailable,
        }
    } else {
        Validation::HeldOut {
            before: Residuals::of(&nominal, held_out),
            after: Residuals::of(&fit.geometry, held_out),
        }
    };
    Ok(Calibration {
        before: Residuals::of(&nominal, measurements),
        after: Residuals::of(&fit.geometry, measurements),
        nominal,
        analysis,
        fit,
        validation,
    })
}

impl Calibration {
    /// The report: data, identifiability, residuals and every parameter's estimate ± σ.
    pub fn report(&self) -> String {
        let mut out = String::new();
        let a = &self.analysis;
        let _ = writeln!(
            out,
            "{} parameters identified from {} poses; not identifiable (kept nominal): {}",
            a.identified.len(),
            self.before.count,
            model::list(&a.unidentifiable)
        );
        let _ = writeln!(
            out,
            "condition number {:.1}, observability index O1 {:.4} m (angles scaled by {:.3} m)",
            a.condition, a.observability, a.reach
        );
        if a.condition > WELL_CONDITIONED {
            let _ = writeln!(
                out,
                "WARNING: condition number above {WELL_CONDITIONED}: some parameters are poorly \
                 determined (large σ below); poses from `armgate calibrate plan` help unless \
                 the arm's geometry itself hides them"
            );
        }
        let _ = writeln!(
            out,
            "fit: {} iterations, residual per coordinate {:.4} mm",
            self.fit.iterations,
            self.fit.sigma * 1e3
        );
        let _ = writeln!(
            out,
            "\nposition error (mm)           poses     mean      rms      max  std dev"
        );
        let mut row = |label: &str, r: &Residuals| {
            let _ = writeln!(
                out,
                "{label:<30}{:>5} {:>8.3} {:>8.3} {:>8.3} {:>8.3}",
                r.count,
                r.mean * 1e3,
                r.rms * 1e3,
                r.max * 1e3,
                r.std_dev * 1e3
            );
        };
        row("fitting poses, nominal", &self.before);
        row("fitting poses, calibrated", &self.after);
        match &self.validation {
            Validation::HeldOut { before, after } => {
                row("held-out poses, nominal", before);
                row("held-out poses, calibrated", after);
            }
            Validation::CrossValidation { folds, after } => {
                row(&format!("{folds}-fold cross-validation"), after);
            }
            Validation::Unavailable => {
                let _ = writeln!(
                    out,
                    "not validated: no held-out poses, and too few poses for {FOLDS}-fold \
                     cross-validation"
                );
            }
        }
        let _ = writeln!(
            out,
            "\nparameter      unit        nominal      estimate     ± σ (1σ)"
        );
        for (p, sd) in self.fit.params.iter().zip(&self.fit.std_dev) {
            let (unit, scale) = p.display_unit();
            let _ = writeln!(
                out,
                "{:<14} {unit:<4} {:>14.5} {:>13.5} {:>12.5}",
                p.to_string(),
                self.nominal.get(*p) * scale,
                self.fit.geometry.get(*p) * scale,
                sd * scale
            );
        }
        out
    }
}
