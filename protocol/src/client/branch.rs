//! The configuration branch of a closed-form IK solution on the wire (`KG`, `KS`, `SQ` 5).
//!
//! Three bits: [`SHOULDER`], [`ELBOW`], [`WRIST`], 0..=7: the configuration as arms name it,
//! taken from the geometry of the joints on every closed-form robot (docs/kinematics.md,
//! "Named configurations", says what each means per robot): set for shoulder right, elbow
//! down, wrist flipped ([`NAMES`]). On a 7–8 joint arm they name a solution together with
//! its redundancy values (θ3, θ5: `KR`); on a prismatic base (hybrid) the wrist bit does not
//! apply (no wrist of three axes) and a `KG` with it is refused. `KG` with
//! [`NEAREST_BRANCH`] moves to the solution nearest the present joints, on whatever branch
//! that is.

/// Shoulder bit: the upper arm right of the base axis seen towards the wrist centre (axis 1
/// up); on a 7–8 joint arm the wrist centre behind the plane of axes 1 and 2 (KUKA's A2 < 0
/// where the elbow is straight); on hybrid θ4 + θ5 > 0.
pub const SHOULDER: u8 = 1;
/// Elbow bit: the elbow below the line from the shoulder to the wrist centre; on a 7–8 joint
/// arm the elbow bent negatively about axis 4 (KUKA's A4 < 0); on hybrid the link from axis
/// 4 to axis 5 short of the vertical.
pub const ELBOW: u8 = 2;
/// Wrist bit: the wrist's middle joint turned negative (its axis against the cross product of
/// the other two wrist axes; KUKA's A6 < 0 on the iiwa); never on hybrid.
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
