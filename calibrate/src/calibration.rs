//! One calibration run: the instrument's registration, identifiability analysis, the robust
//! fit, validation, the checks that refuse a result, and the report.

use std::fmt::Write as _;

use armgate_core::config::RobotConfig;

use crate::fit::{self, Fit, FitError, Measurement, Residuals};
use crate::identify::{self, Identifiability};
use crate::instrument::{self, Placement};
use crate::model::{self, FitSet, Geometry, MeasuredIn, Param};
use crate::robust::{self, Rejected};

/// Folds of the cross-validation run when no held-out poses are given.
pub const FOLDS: usize = 5;
/// Above this condition number the poses determine the parameters poorly: the fit may match
/// them and be wrong elsewhere (published guidance: ≲ 100).
pub const WELL_CONDITIONED: f64 = 100.0;
/// A fitted length that moves further than this from its nominal value (m) is reported as a
/// likely modelling error (a wrong file, unit or convention), not a property of the robot.
pub const LENGTH_TOLERANCE: f64 = 5e-3;
/// The same for an angle (rad): 1°.
pub const ANGLE_TOLERANCE: f64 = std::f64::consts::PI / 180.0;
/// A residual per coordinate more than this many times the stated instrument noise means the
/// model does not explain the data: the result is refused.
pub const NOISE_FACTOR: f64 = 3.0;

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
    /// The robot's geometry as its file states it, seen through the registered instrument.
    pub nominal: Geometry,
    /// Which parameters were fitted and which could not be.
    pub analysis: Identifiability,
    /// The fit (of the poses kept).
    pub fit: Fit,
    /// The instrument's frame in the robot's base frame, with its σ (the world frame's, given,
    /// when measured in it).
    pub instrument: Placement,
    /// The measurements set aside as outliers, with their residuals.
    pub rejected: Vec<Rejected>,
    /// The residual beyond which a measurement is set aside (m).
    pub threshold: f64,
    /// True if more measurements lay beyond it than may be set aside.
    pub too_many_outliers: bool,
    /// The instrument's stated noise per coordinate (m), if given.
    pub noise: Option<f64>,
    /// Errors at the fitting poses kept, nominal model.
    pub before: Residuals,
    /// Errors at the fitting poses, calibrated model.
    pub after: Residuals,
    /// Errors on poses the fit did not see.
    pub validation: Validation,
}

/// What a calibration fits, and what it knows of the instrument.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Options {
    /// Which robot constants to fit.
    pub set: FitSet,
    /// The frame of the measured positions.
    pub measured_in: MeasuredIn,
    /// The instrument's stated noise per coordinate (m), if known.
    pub noise: Option<f64>,
}

impl Options {
    /// Every identifiable constant, measured in an instrument's frame, with this noise.
    pub fn with_noise(noise: Option<f64>) -> Self {
        Self {
            noise,
            ..Self::default()
        }
    }
}

/// Calibrates `config` from `measurements` — taken in an instrument's frame, which is
/// registered first and then fitted with the robot, unless they are in the world frame —
/// checking the result on `held_out` poses (same instrument, same place), or by
/// cross-validation when there are none.
pub fn calibrate(
    config: &RobotConfig,
    measurements: &[Measurement],
    held_out: &[Measurement],
    options: &Options,
) -> Result<Calibration, FitError> {
    let Options {
        set,
        measured_in,
        noise,
    } = *options;
    let unregistered = Geometry::new(config);
    if measurements.is_empty() {
        return Err(FitError::NoMeasurements);
    }
    if let Some(pose) = measurements
        .iter()
        .chain(held_out)
        .position(|m| m.q.len() != unregistered.dof())
    {
        return Err(FitError::WrongJointCount { pose });
    }
    let registration =
        instrument::register(&unregistered, measurements).ok_or(FitError::Unregistrable)?;
    let nominal = match measured_in {
        MeasuredIn::Instrument => unregistered.registered(registration.transform),
        MeasuredIn::World => unregistered,
    };
    let poses: Vec<Vec<f64>> = measurements.iter().map(|m| m.q.clone()).collect();
    let analysis = identify::analyse(&nominal, &nominal.candidates(set, measured_in), &poses);
    let robust = robust::fit(
        &nominal,
        &analysis.identified,
        measurements,
        &registration.gross,
        noise,
    )?;
    let kept: Vec<Measurement> = robust
        .kept
        .iter()
        .filter_map(|k| measurements.get(*k).cloned())
        .collect();
    let fit = robust.fit;
    let validation = if held_out.is_empty() {
        match fit::cross_validate(&nominal, &analysis.identified, &kept, FOLDS) {
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
        before: Residuals::of(&nominal, &kept),
        after: Residuals::of(&fit.geometry, &kept),
        instrument: Placement::fitted(&fit),
        nominal,
        analysis,
        fit,
        rejected: robust.rejected,
        threshold: robust.threshold,
        too_many_outliers: robust.too_many,
        noise,
        validation,
    })
}

impl Calibration {
    /// Why the result should not be used: worse than the nominal model on poses the fit did
    /// not see, a residual far above the stated noise, or more outliers than may be set aside.
    /// `armgate-calibrate` writes nothing then, unless forced.
    pub fn problems(&self) -> Vec<String> {
        let mut problems = Vec::new();
        let (label, before, after) = match &self.validation {
            Validation::HeldOut { before, after } => ("held-out", before.mean, after.mean),
            Validation::CrossValidation { after, .. } => {
                ("cross-validated", self.before.mean, after.mean)
            }
            Validation::Unavailable => ("fitting-pose", self.before.mean, self.after.mean),
        };
        if after >= before {
            problems.push(format!(
                "the calibrated model is no better than the nominal one ({label} mean error \
                 {:.3} mm against {:.3} mm)",
                after * 1e3,
                before * 1e3
            ));
        }
        if let Some(noise) = self.noise
            && self.fit.sigma > NOISE_FACTOR * noise
        {
            problems.push(format!(
                "the residual per coordinate, {:.4} mm, is more than {NOISE_FACTOR} times the \
                 stated noise {:.4} mm: the model does not explain the data",
                self.fit.sigma * 1e3,
                noise * 1e3
            ));
        }
        if self.too_many_outliers {
            problems.push(format!(
                "more than {:.0} % of the measurements lie beyond {:.4} mm: not a bad line but \
                 a model or a data set that does not fit",
                robust::MAX_REJECTED * 100.0,
                self.threshold * 1e3
            ));
        }
        problems
    }

    /// The fitted robot constants further from nominal than the tolerances: likely modelling
    /// errors. Each with its move (m or rad).
    pub fn large_moves(&self) -> Vec<(Param, f64)> {
        self.fit
            .params
            .iter()
            .filter(|p| !p.is_instrument())
            .map(|p| (*p, self.fit.geometry.get(*p) - self.nominal.get(*p)))
            .filter(|(p, moved)| {
                let tolerance = if p.is_angle() {
                    ANGLE_TOLERANCE
                } else {
                    LENGTH_TOLERANCE
                };
                moved.abs() > tolerance
            })
            .collect()
    }

    /// The report: data, identifiability, the instrument, residuals, warnings and every robot
    /// parameter's estimate ± σ.
    pub fn report(&self) -> String {
        let mut out = String::new();
        let a = &self.analysis;
        let robot_fitted = a.identified.iter().filter(|p| !p.is_instrument()).count();
        let instrument_fitted = robot_fitted < a.identified.len();
        let _ = writeln!(
            out,
            "{robot_fitted} robot parameters{} identified from {} poses; not identifiable (kept \
             nominal): {}",
            if instrument_fitted {
                " and the instrument's frame (6)"
            } else {
                ""
            },
            self.before.count + self.rejected.len(),
            model::list(&a.unidentifiable)
        );
        let _ = writeln!(
            out,
            "{}",
            if instrument_fitted {
                "the robot's base frame is its own: joint 1's constants that the instrument's \
                 frame could also explain stay nominal, the [base] frame is not fitted"
            } else {
                "measured in the robot's world frame: no instrument frame fitted; joint 1's \
                 constants and the [base] are fitted where identifiable"
            }
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
        let noise = match self.noise {
            Some(n) => format!(" (stated noise {:.4} mm)", n * 1e3),
            None => " (no noise stated: --noise-mm)".into(),
        };
        let _ = writeln!(
            out,
            "fit: {} iterations, residual per coordinate {:.4} mm{noise}",
            self.fit.iterations,
            self.fit.sigma * 1e3
        );
        if self.rejected.is_empty() {
            let _ = writeln!(
                out,
                "outliers: none beyond {:.4} mm ({}σ)",
                self.threshold * 1e3,
                robust::K
            );
        } else {
            let _ = writeln!(
                out,
                "outliers set aside (residual beyond {:.4} mm, {}σ):",
                self.threshold * 1e3,
                robust::K
            );
            for r in &self.rejected {
                let _ = writeln!(out, "  {}: residual {:.3} mm", r.name, r.residual * 1e3);
            }
        }
        if instrument_fitted {
            let _ = write!(out, "\n{}", self.instrument.report());
        }
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
            "(nominal: the robot file as it is, in the instrument's registered frame)"
        );
        for (p, moved) in self.large_moves() {
            let (unit, scale) = p.display_unit();
            let _ = writeln!(
                out,
                "WARNING: {p} moved {:.3} {unit} from nominal (tolerance {} mm / {}°): more \
                 likely a modelling error (the wrong robot file, a unit, a DH convention) than \
                 the robot",
                moved * scale,
                LENGTH_TOLERANCE * 1e3,
                ANGLE_TOLERANCE.to_degrees()
            );
        }
        for problem in self.problems() {
            let _ = writeln!(out, "ERROR: {problem}");
        }
        let _ = writeln!(
            out,
            "\nparameter      unit        nominal      estimate     ± σ (1σ)"
        );
        let rows = self.fit.params.iter().zip(&self.fit.std_dev);
        for (p, sd) in rows.filter(|(p, _)| !p.is_instrument()) {
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
