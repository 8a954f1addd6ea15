//! Kinematics of a serial chain built from a robot description.
//!
//! * [`Chain`]: forward kinematics of the tool and of every link frame, the geometric Jacobian
//!   and manipulability.
//! * [`Chain::solve_tracking`] / [`Chain::solve_global`]: inverse position kinematics from a
//!   nearby seed (the per-tick case) or from anywhere (deterministic random restarts).
//! * [`diverges`]: the seed's divergence guard.
//! * [`Chain::joint_rates`]: inverse velocity kinematics with a null-space term.

mod chain;
mod ik;
mod jacobian;

mod velocity;

pub use crate::math::Joints;
pub use chain::{Chain, KinematicsError};
pub use ik::{IkError, IkResult, IkSolution, diverges};
pub use jacobian::Jacobian;
