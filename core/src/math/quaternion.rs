//! Unit quaternions in the wire order of the client protocol: (x, y, z, w), scalar last.

use super::{Rotation, Vec3};

/// A quaternion (x, y, z, w) = (k·sin(θ/2), cos(θ/2)) for a rotation by θ about unit axis k
/// (Craig's Euler parameters ε1..ε4, Hamilton convention).
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

    /// This quaternion scaled to unit norm, or `None` if its norm is zero or not finite (the
    /// seed divided by the norm unchecked and produced NaN poses, spec §9 item 11).
    pub fn normalized(self) -> Option<Self> {
        let n = libm::sqrt(self.x * self.x + self.y * self.y + self.z * self.z + self.w * self.w);
        if !n.is_finite() || n < 1e-12 {
            return None;
        }
        let s = 1.0 / n;
        Some(Self::new(self.x * s, self.y * s, self.z * s, self.w * s))
    }

    /// The rotation matrix of a unit quaternion (spec §2.4).
    pub fn to_rotation(self) -> Rotation {
        let Self { x, y, z, w } = self;
        Rotation::from_rows([
            [
                w * w + x * x - y * y - z * z,
                2.0 * (x * y - w * z),
                2.0 * (x * z + w * y),
            ],
            [
                2.0 * (x * y + w * z),
                w * w - x * x + y * y - z * z,
                2.0 * (y * z - w * x),
            ],
            [
                2.0 * (x * z - w * y),
                2.0 * (y * z + w * x),
                w * w - x * x - y * y + z * z,
            ],
        ])
    }

    /// The quaternion of a rotation, with the scalar part `w ≥ 0` as the seed's PS reply has it.
    ///
    /// Uses Shepperd's method (largest of the four squared components), so it is accurate for
    /// every rotation; the seed's axis–angle path divided by zero for half turns about axes in
    /// the x–y plane (spec §9 item 4). For a half turn (w = 0) the sign makes the first nonzero
    /// of z, y, x positive, which matches the seed where the seed is defined.
    pub fn from_rotation(r: &Rotation) -> Self {
        let [[r00, r01, r02], [r10, r11, r12], [r20, r21, r22]] = r.to_rows();
        let tr = r00 + r11 + r22;
        let q = if tr >= r00 && tr >= r11 && tr >= r22 {
            let s = 2.0 * libm::sqrt(1.0 + tr);
            Self::new((r21 - r12) / s, (r02 - r20) / s, (r10 - r01) / s, 0.25 * s)
        } else if r00 >= r11 && r00 >= r22 {
            let s = 2.0 * libm::sqrt(1.0 + r00 - r11 - r22);
            Self::new(0.25 * s, (r01 + r10) / s, (r02 + r20) / s, (r21 - r12) / s)
        } else if r11 >= r22 {
            let s = 2.0 * libm::sqrt(1.0 + r11 - r00 - r22);
            Self::new((r01 + r10) / s, 0.25 * s, (r12 + r21) / s, (r02 - r20) / s)
        } else {
            let s = 2.0 * libm::sqrt(1.0 + r22 - r00 - r11);
            Self::new((r02 + r20) / s, (r12 + r21) / s, 0.25 * s, (r10 - r01) / s)
        };
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

    /// The vector part (x, y, z).
    pub fn vector(self) -> Vec3 {
        Vec3::new(self.x, self.y, self.z)
    }
}
