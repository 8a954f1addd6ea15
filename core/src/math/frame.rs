//! Rigid transforms (frames) and the displacement between two frames.

use nalgebra::{IsometryMatrix3, Matrix3, Rotation3, Vector3, Vector6};

use super::rotation_vector;

/// A rigid transform: the pose of a frame (rotation matrix and origin) in a reference frame.
pub type Frame = IsometryMatrix3<f64>;

/// A 6-vector `[vx, vy, vz, wx, wy, wz]` of linear and angular parts: a velocity twist, or a
/// small displacement (m and rad, the angular part a rotation vector in the base frame).
pub type Twist = Vector6<f64>;

/// Craig's modified DH transform `RotX(alpha) · TransX(a) · RotZ(theta) · TransZ(d)`
/// (KDL `Frame::DH_Craig1989(a, alpha, d, theta)`).
pub fn dh(a: f64, alpha: f64, d: f64, theta: f64) -> Frame {
    let (sa, ca) = libm::sincos(alpha);
    let (st, ct) = libm::sincos(theta);
    #[rustfmt::skip]
    let rotation = Matrix3::new(
        ct, -st, 0.0,
        st * ca, ct * ca, -sa,
        st * sa, ct * sa, ca,
    );
    Frame::from_parts(
        Vector3::new(a, -sa * d, ca * d).into(),
        Rotation3::from_matrix_unchecked(rotation),
    )
}

/// The displacement from `from` to `to` in base coordinates: `(p_to − p_from, rotvec)` where
/// rotvec is the rotation vector of `R_to · R_fromᵀ` (KDL `diff`, with a robust log map).
pub fn diff(from: &Frame, to: &Frame) -> Twist {
    let linear = to.translation.vector - from.translation.vector;
    let angular = rotation_vector(&from.rotation.rotation_to(&to.rotation));
    Vector6::new(
        linear.x, linear.y, linear.z, angular.x, angular.y, angular.z,
    )
}

/// The seed's mixed distance `|Δp| + |Δθ|` (m + rad, 1 m ≡ 1 rad).
pub fn dist(a: &Frame, b: &Frame) -> f64 {
    let d = diff(a, b);
    d.fixed_rows::<3>(0).norm() + d.fixed_rows::<3>(3).norm()
}

/// True if every entry of the frame is finite.
pub fn is_finite(f: &Frame) -> bool {
    let finite = |v: &f64| v.is_finite();
    f.rotation.matrix().iter().all(finite) && f.translation.vector.iter().all(finite)
}
