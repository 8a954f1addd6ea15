//! The configuration branch of a closed-form IK solution on the wire (`KG`, `KS`, `SQ` 5).
//!
//! Three bits: [`SHOULDER`], [`ELBOW`], [`WRIST`], 0..=7. On a six-revolute-joint arm (axes
//! 2 and 3 parallel: ranger-mk1, puma560, ur5) they are the configuration as arms name it,
//! taken from the geometry of the joints (docs/kinematics.md): set for shoulder right, elbow
//! down, wrist flipped ([`NAMES`]). On a 7–8 joint arm and a prismatic base they are the
//! solver's roots, each set when that joint takes the second of its two. `KG` with
//! [`NEAREST_BRANCH`] moves to the solution nearest the present joints, on whatever branch
//! that is.

/// Shoulder bit: the upper arm right of the base axis seen towards the wrist centre (axis 1
/// up); on a 7–8 joint arm the second root of θ1/θ2.
pub const SHOULDER: u8 = 1;
/// Elbow bit: the elbow below the line from the shoulder to the wrist centre; on a 7–8 joint
/// arm the second root of θ4.
pub const ELBOW: u8 = 2;
/// Wrist bit: the wrist's middle joint turned negative (its axis against the cross product of
/// the other two wrist axes); on a 7–8 joint arm the second root of the wrist.
pub const WRIST: u8 = 4;
/// Each bit's two names, clear then set, with their one-letter short forms: what `armgate
/// ik` prints and `--branch` reads (`shoulder-left,elbow-up,wrist-noflip` or `lun`).
pub const NAMES: [(u8, [(&str, char); 2]); 3] = [
    (SHOULDER, [("shoulder-left", 'l'), ("shoulder-right", 'r')]),
    (ELBOW, [("elbow-up", 'u'), ("elbow-down", 'd')]),
    (WRIST, [("wrist-noflip", 'n'), ("wrist-flip", 'f')]),
];
/// `KG` index: no branch chosen (with [`CHOSEN`](super::redundancy::CHOSEN): 8 | `CHOSEN`), the solution nearest the present joints.
pub const NEAREST_BRANCH: u8 = 8;
/// `SQ` index of the present branch (reply f0: the bits, or −1 for none).
pub const BRANCH_INDEX: u8 = 5;
/// `SK` f6 on a robot without a closed form (otherwise the number of solutions).
pub const NO_CLOSED_FORM: f32 = -1.0;
/// `SK` index when the requested solution does not exist (fewer solutions).
pub const NO_SOLUTION: u8 = 0xFF;
