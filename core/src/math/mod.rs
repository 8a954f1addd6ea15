//! Small fixed-size geometry: 3-vectors, rotations, rigid frames and the orientation
//! conventions of the client protocol (spec §2.4).
//!
//! Hand-written rather than a general matrix library: every type is a few `f64`s, every
//! operation is branch-light straight-line code, which keeps the per-tick cost on the
//! Cortex-M7 predictable.

mod frame;
mod quaternion;
mod rotation;
mod vec3;

pub use frame::{Frame, Twist};
pub use quaternion::Quaternion;
pub use rotation::Rotation;
pub use vec3::Vec3;
