//! armgate's core: everything that decides anything about the arm.
//!
//! The core is `no_std`, never allocates, never panics on any input (fallible operations return
//! typed errors) and bounds every loop by a count, so that the host simulation and the
//! microcontroller compute identical results. "Never panics" is checked at link time for what
//! runs every cycle and on every datagram: `panic-check/` links the control tick, request
//! parsing and command handling for the Cortex-M7 with a panic handler that cannot link. It does no I/O: the shells (`firmware`, `host-sim`)
//! only move bytes and time.
//!
//! * [`command`]: the client protocol's commands mapped onto the controller, and the relay of
//!   unsolicited warnings.
//! * [`cycle`]: the control tick every shell runs: requests, drives, control step, notices.
//! * [`math`]: vectors, rotations, frames, quaternion and roll/pitch/yaw conversions.
//! * [`geometry`]: segment, capsule and box distances (the arm's envelope).
//! * [`config`]: the robot description ([`config::RobotConfig`]) and its validation.
//! * [`kinematics`]: forward kinematics, Jacobians, inverse position and velocity kinematics.
//! * [`motion`]: generators, sequences, limiters, the mode switch and the control step.
//! * [`drives`]: the servo drives on the CAN bus (start-up, PT streaming, faults).
//! * `sim` (feature `sim`): the simulations, kept apart from product code: arms, drives,
//!   the CAN bus.
//! * [`rng`]: the small deterministic random generator used by global IK and by tests.
#![cfg_attr(not(any(test, feature = "std")), no_std)]

pub mod command;
pub mod config;
pub mod cycle;
pub mod drives;
pub mod geometry;
pub mod kinematics;
pub mod math;
pub mod motion;
pub mod rng;
mod saturate;
#[cfg(feature = "sim")]
pub mod sim;

/// The largest number of joints a robot may have (the seed's Ranger Mark II has 8): as many
/// as the protocol's joint banks address.
pub const MAX_JOINTS: usize = armgate_protocol::client::banks::MAX_JOINTS;
