//! Kinematic calibration of an armgate robot file from measured tool positions.
//!
//! An instrument (laser tracker, measuring arm) measures the tool position at a few dozen joint
//! configurations; calibration fits the robot file's geometry to them:
//!
//! * [`model`]: the geometry as named parameters (joint offsets, DH lengths and angles, Hayati's
//!   β for nearly parallel axes, base and tool frames) and the tool position they give.
//! * [`identify`]: the identification Jacobian and which parameters the poses determine.
//! * [`instrument`]: the instrument's frame: registration, placement, its file.
//! * [`fit`]: Levenberg–Marquardt, parameter uncertainties, residual statistics.
//! * [`robust`]: outlier rejection, so that one bad line cannot move the fit.
//! * [`calibration`]: one run with its validation and report.
//! * [`plan`]: which poses to measure.
//! * [`measurements`], [`robot_file`]: the files read and written.
//! * [`world`]: a world `[base]` in the instrument's frame, and the workspace carried into it.
//! * [`sim`]: simulated metrology (error injection, noisy measurements) for tests and examples.
//!
//! `docs/calibration.md` explains the method and shows results.

pub mod calibration;
pub mod fit;
pub mod identify;
pub mod instrument;
pub mod measurements;
pub mod model;
pub mod plan;
pub mod robot_file;
pub mod robust;
pub mod sim;
pub mod world;
