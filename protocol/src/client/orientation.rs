//! Orientations as the client protocol carries them (spec §2.4): quaternions in wire order
//! (x, y, z, w), scalar last, w ≥ 0, and the seed's roll/pitch/yaw extraction. The arithmetic is
//! nalgebra's; only the protocol's conventions live here, shared by the controller and the client.

use core::f64::consts::PI;

use nalgebra::{Rotation3, UnitQuaternion, Vector3};

/// Roll, pitch, yaw of `r`, extracted as the seed does (spec §2.4), including its gimbal-lock
/// branch (|r20| > 1 − 1e-6: yaw = 0); the inverse of `Rotation3::from_euler_angles`.
pub fn rpy(r: &Rotation3<f64>) -> [f64; 3] {
    let m = r.matrix();
    if libm::fabs(m.m31) > 1.0 - 1e-6 {
        let sign = if m.m31 < 0.0 { -1.0 } else { 1.0 };
        [-sign * libm::atan2(m.m12, m.m22), -sign * PI / 2.0, 0.0]
    } else {
        [
            libm::atan2(m.m32, m.m33),
            libm::atan2(-m.m31, libm::sqrt(m.m11 * m.m11 + m.m21 * m.m21)),
            libm::atan2(m.m21, m.m11),
        ]
    }
}

/// A quaternion in wire order (x, y, z, w) = (k·sin(θ/2), cos(θ/2)) for a rotation by θ about
/// unit axis k (Craig's Euler parameters ε1..ε4, Hamilton convention). Converts to and from
/// nalgebra, whose constructor takes w first and whose sign is free.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quaternion {
    /// ε1 = kx·sin(θ/2).
    pub x: f64,
    /// ε2 = ky·sin(θ/2).
    pub y: f64,
    /// ε3 = kz·sin(θ/2).
    pub z: f64,
    /// ε4 = cos(θ/2).
    pub w: f64,
}

impl Quaternion {
    /// The identity rotation (0, 0, 0, 1).
    pub const IDENTITY: Self = Self::new(0.0, 0.0, 0.0, 1.0);

    /// A quaternion from its wire-order components.
    pub const fn new(x: f64, y: f64, z: f64, w: f64) -> Self {
        Self { x, y, z, w }
    }

    /// The components in wire order `[x, y, z, w]`.
    pub const fn to_array(self) -> [f64; 4] {
        [self.x, self.y, self.z, self.w]
    }

    /// The vector part (x, y, z).
    pub fn vector(self) -> Vector3<f64> {
        Vector3::new(self.x, self.y, self.z)
    }

    /// This quaternion scaled to unit norm, or `None` if its norm is zero or not finite (the
    /// seed divided by the norm unchecked and produced NaN poses, spec §9 item 11).
    pub fn normalized(self) -> Option<Self> {
        let q = self.to_nalgebra().into_inner();
        let n = q.norm();
        if !n.is_finite() || n < 1e-12 {
            return None;
        }
        Some(Self::from_nalgebra(&(q / n)))
    }

    /// The rotation matrix of a unit quaternion (spec §2.4).
    pub fn to_rotation(self) -> Rotation3<f64> {
        self.to_nalgebra().to_rotation_matrix()
    }

    /// The quaternion of a rotation, with the scalar part `w ≥ 0` as the seed's PS reply has it.
    ///
    /// nalgebra's conversion is Shepperd's method (largest of the four squared components), so
    /// it is accurate for every rotation; the seed's axis–angle path divided by zero for half
    /// turns about axes in the x–y plane (spec §9 item 4). For a half turn (w = 0) the sign
    /// makes the first nonzero of z, y, x positive, which matches the seed where it is defined.
    pub fn from_rotation(r: &Rotation3<f64>) -> Self {
        let q = Self::from_nalgebra(&UnitQuaternion::from_rotation_matrix(r));
        let flip = if q.w != 0.0 {
            q.w < 0.0
        } else if q.z != 0.0 {
            q.z < 0.0
        } else if q.y != 0.0 {
            q.y < 0.0
        } else {
            q.x < 0.0
        };
        if flip {
            Self::new(-q.x, -q.y, -q.z, -q.w)
        } else {
            q
        }
    }

    /// nalgebra's quaternion with the same components, taken as unit (not normalised).
    fn to_nalgebra(self) -> UnitQuaternion<f64> {
        let q = nalgebra::Quaternion::new(self.w, self.x, self.y, self.z);
        UnitQuaternion::new_unchecked(q)
    }

    fn from_nalgebra(q: &nalgebra::Quaternion<f64>) -> Self {
        Self::new(q.i, q.j, q.k, q.w)
    }
}
