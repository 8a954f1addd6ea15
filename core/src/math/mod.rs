//! Geometry on nalgebra's fixed-size types, plus the conventions of the client protocol
//! (spec §2.4) where they differ from nalgebra's.
//!
//! * [`Frame`]: a rigid transform, nalgebra's isometry with a rotation *matrix* (forward
//!   kinematics and the Jacobian read the matrix columns directly); [`Twist`]: a 6-vector
//!   `[vx, vy, vz, wx, wy, wz]`.
//! * RPY: `Rotation3::from_euler_angles(roll, pitch, yaw)` is the seed's `Rz · Ry · Rx`; only
//!   the extraction differs, in the seed's gimbal-lock branch ([`rpy`]).
//! * The log map: nalgebra's `scaled_axis` returns zero at half turns (the KDL defect of spec
//!   §9 item 4) and loses precision below 1e-8 rad (it takes `acos` of the trace), so
//!   [`rotation_vector`] keeps the robust one the IK needs.
//! * Quaternions on the wire are (x, y, z, w) with w ≥ 0 ([`Quaternion`]); nalgebra's
//!   constructor takes w first and leaves the sign free. Both conventions are wire rules, so
//!   they live in `armgate_protocol::client` (shared with the client) and are re-exported here.

mod frame;
mod joints;
mod rotation;
mod sqrt;

pub use armgate_protocol::client::{Quaternion, rpy};
pub use frame::{Frame, Twist, dh, diff, dist, is_finite};
pub use joints::Joints;
pub use nalgebra::{Rotation3, SVector, Translation3, UnitQuaternion, Vector3, Vector6};
pub use rotation::rotation_vector;
pub use sqrt::sqrt;
