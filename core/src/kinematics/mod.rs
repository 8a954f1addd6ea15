//! Kinematics of a serial chain built from a robot description.
//!
//! * [`Chain`]: forward kinematics of the tool and of every link frame, the geometric Jacobian
//!   and manipulability.
//! * [`Chain::solve_tracking`] / [`Chain::solve_global`]: inverse position kinematics from a
//!   nearby seed (the per-tick case) or from anywhere (deterministic random restarts);
//!   [`Chain::solve_tracking_after`] reuses the last solve's final pose evaluation
//!   ([`LastEvaluation`]) when the seed is that solve's answer, as in the control tick.
//! * [`Chain::solve_all`] / [`Chain::solve_nearest`]: every solution in closed form, for the
//!   [`Family`] detected from the geometry (subproblem decomposition).
//! * [`diverges`]: the seed's divergence guard.
//! * [`Chain::joint_rates`]: inverse velocity kinematics with a null-space term.

mod calibrated;
mod chain;
mod closed_form;
mod configuration;
mod descent;
mod evaluation;
mod family;
mod global;
mod ik;
mod jacobian;
mod prismatic_base;
mod screws;
mod spherical_shoulder;
mod spherical_wrist;
mod subproblems;
mod sweep;
mod three_parallel;
mod velocity;

pub use crate::math::Joints;
pub use chain::{Chain, KinematicsError};
pub use closed_form::{Branch, BranchSolution, CHECK, MAX_SOLUTIONS, SeedAngles, Solutions};
pub use evaluation::LastEvaluation;
pub use family::{Family, FamilyFit};
pub use global::GlobalSearch;
pub use ik::{IkError, IkResult, IkSolution, TRACKING_JUMP, diverges};
pub use jacobian::Jacobian;
pub use sweep::Levers;
