//! The configuration branch of a closed-form IK solution on the wire (`KG`, `KS`, `SQ` 5).
//!
//! Three bits: [`SHOULDER`], [`ELBOW`], [`WRIST`], each set when that joint takes the second of
//! its two roots (the mirrored configuration); 0..=7. `KG` with [`NEAREST_BRANCH`] moves to the
//! solution nearest the present joints, on whatever branch that is.

/// Shoulder bit: the second root of θ1 (of θ1/θ2 on a 7–8 joint arm).
pub const SHOULDER: u8 = 1;
/// Elbow bit: the second root of θ3 (of θ4 on a 7–8 joint arm).
pub const ELBOW: u8 = 2;
/// Wrist bit: the second root of the wrist (θ4/θ5, θ5 for three parallel axes, θ5/θ6 or θ6/θ7
/// on a 7–8 joint arm).
pub const WRIST: u8 = 4;
/// `KG` index: no branch chosen (with [`CHOSEN`](super::redundancy::CHOSEN): 8 | `CHOSEN`), the solution nearest the present joints.
pub const NEAREST_BRANCH: u8 = 8;
/// `SQ` index of the present branch (reply f0: the bits, or −1 for none).
pub const BRANCH_INDEX: u8 = 5;
/// `SK` f6 on a robot without a closed form (otherwise the number of solutions).
pub const NO_CLOSED_FORM: f32 = -1.0;
/// `SK` index when the requested solution does not exist (fewer solutions).
pub const NO_SOLUTION: u8 = 0xFF;
