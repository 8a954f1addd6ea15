//! 3×3 rotation matrices.

use core::f64::consts::PI;
use core::ops::Mul;

use super::Vec3;

/// A rotation matrix, stored as its three columns (the rotated x, y and z axes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rotation {
    /// Columns: images of the unit x, y and z axes.
    pub cols: [Vec3; 3],
}

impl Default for Rotation {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Rotation {
    /// The identity rotation.
    pub const IDENTITY: Self = Self {
        cols: [Vec3::X, Vec3::Y, Vec3::Z],
    };

    /// A rotation from its columns.
    pub const fn from_cols(x: Vec3, y: Vec3, z: Vec3) -> Self {
        Self { cols: [x, y, z] }
    }

    /// A rotation from rows `[[r00, r01, r02], [r10, ..], [r20, ..]]`.
    pub const fn from_rows(r: [[f64; 3]; 3]) -> Self {
        Self::from_cols(
            Vec3::new(r[0][0], r[1][0], r[2][0]),
            Vec3::new(r[0][1], r[1][1], r[2][1]),
            Vec3::new(r[0][2], r[1][2], r[2][2]),
        )
    }

    /// The rows `[[r00, r01, r02], ..]`.
    pub const fn to_rows(&self) -> [[f64; 3]; 3] {
        let [x, y, z] = self.cols;
        [[x.x, y.x, z.x], [x.y, y.y, z.y], [x.z, y.z, z.z]]
    }

    /// Rotation about x by `a` rad.
    pub fn rot_x(a: f64) -> Self {
        let (s, c) = libm::sincos(a);
        Self::from_cols(Vec3::X, Vec3::new(0.0, c, s), Vec3::new(0.0, -s, c))
    }

    /// Rotation about y by `a` rad.
    pub fn rot_y(a: f64) -> Self {
        let (s, c) = libm::sincos(a);
        Self::from_cols(Vec3::new(c, 0.0, -s), Vec3::Y, Vec3::new(s, 0.0, c))
    }

    /// Rotation about z by `a` rad.
    pub fn rot_z(a: f64) -> Self {
        let (s, c) = libm::sincos(a);
        Self::from_cols(Vec3::new(c, s, 0.0), Vec3::new(-s, c, 0.0), Vec3::Z)
    }

    /// `Rz(yaw) · Ry(pitch) · Rx(roll)`: Craig's X-Y-Z fixed angles (spec §2.4, KDL `RPY`).
    pub fn from_rpy(roll: f64, pitch: f64, yaw: f64) -> Self {
        let (sa, ca) = libm::sincos(yaw);
        let (sb, cb) = libm::sincos(pitch);
        let (sc, cc) = libm::sincos(roll);
        Self::from_rows([
            [ca * cb, ca * sb * sc - sa * cc, ca * sb * cc + sa * sc],
            [sa * cb, sa * sb * sc + ca * cc, sa * sb * cc - ca * sc],
            [-sb, cb * sc, cb * cc],
        ])
    }

    /// Roll, pitch, yaw of this rotation, extracted as the seed does (spec §2.4), including its
    /// gimbal-lock branch (|r20| > 1 − 1e-6: yaw = 0).
    pub fn to_rpy(&self) -> [f64; 3] {
        let [[r00, r01, _], [r10, r11, _], [r20, r21, r22]] = self.to_rows();
        if libm::fabs(r20) > 1.0 - 1e-6 {
            let sign = if r20 < 0.0 { -1.0 } else { 1.0 };
            [-sign * libm::atan2(r01, r11), -sign * PI / 2.0, 0.0]
        } else {
            [
                libm::atan2(r21, r22),
                libm::atan2(-r20, libm::sqrt(r00 * r00 + r10 * r10)),
                libm::atan2(r10, r00),
            ]
        }
    }

    /// The rotation by `|v|` rad about `v/|v|` (the exponential map, Rodrigues' formula).
    pub fn from_rotation_vector(v: Vec3) -> Self {
        let t2 = v.norm_squared();
        // Taylor coefficients near zero keep the formula exact to rounding without dividing by θ.
        let (a, b) = if t2 < 1e-12 {
            (1.0 - t2 / 6.0, 0.5 - t2 / 24.0)
        } else {
            let t = libm::sqrt(t2);
            let (s, c) = libm::sincos(t);
            (s / t, (1.0 - c) / t2)
        };
        // R = I + a[v]× + b[v]×²; [v]×² = v vᵀ − |v|² I.
        let col = |e: Vec3| e + v.cross(e) * a + (v * v.dot(e) - e * t2) * b;
        Self::from_cols(col(Vec3::X), col(Vec3::Y), col(Vec3::Z))
    }

    /// The rotation vector (axis × angle, angle in [0, π]) of this rotation: the logarithm map.
    ///
    /// Robust for every rotation, including half turns, where the seed's KDL `GetRot` returned
    /// zero (spec §9 item 4): near π the axis comes from the symmetric part of the matrix.
    pub fn rotation_vector(&self) -> Vec3 {
        let [[r00, r01, r02], [r10, r11, r12], [r20, r21, r22]] = self.to_rows();
        // v = sin θ · k
        let v = Vec3::new(r21 - r12, r02 - r20, r10 - r01) * 0.5;
        let c = ((r00 + r11 + r22 - 1.0) * 0.5).clamp(-1.0, 1.0);
        let s = v.norm();
        let theta = libm::atan2(s, c);
        if theta < 1e-6 {
            // θ/sin θ ≈ 1 + θ²/6
            return v * (1.0 + theta * theta / 6.0);
        }
        if c > -0.5 {
            return v * (theta / s);
        }
        // θ > 120°: sin θ is small and inaccurate; use (R + Rᵀ)/2 − cI = (1 − c) k kᵀ.
        let one_c = 1.0 - c;
        let b = [
            [r00 - c, (r01 + r10) * 0.5, (r02 + r20) * 0.5],
            [(r01 + r10) * 0.5, r11 - c, (r12 + r21) * 0.5],
            [(r02 + r20) * 0.5, (r12 + r21) * 0.5, r22 - c],
        ];
        let [b0, b1, b2] = b;
        let k = if b0[0] >= b1[1] && b0[0] >= b2[2] {
            let kx = libm::sqrt(b0[0] / one_c);
            Vec3::new(kx, b0[1] / (one_c * kx), b0[2] / (one_c * kx))
        } else if b1[1] >= b2[2] {
            let ky = libm::sqrt(b1[1] / one_c);
            Vec3::new(b1[0] / (one_c * ky), ky, b1[2] / (one_c * ky))
        } else {
            let kz = libm::sqrt(b2[2] / one_c);
            Vec3::new(b2[0] / (one_c * kz), b2[1] / (one_c * kz), kz)
        };
        let k = k * (1.0 / k.norm());
        let k = if k.dot(v) < 0.0 { -k } else { k };
        k * theta
    }

    /// The rotation angle in [0, π].
    pub fn angle(&self) -> f64 {
        self.rotation_vector().norm()
    }

    /// The inverse rotation.
    pub fn transpose(&self) -> Self {
        Self::from_rows([
            self.cols[0].to_array(),
            self.cols[1].to_array(),
            self.cols[2].to_array(),
        ])
    }

    /// `Rᵀ · v`: a vector expressed in this rotation's frame.
    pub fn transpose_mul(&self, v: Vec3) -> Vec3 {
        Vec3::new(
            self.cols[0].dot(v),
            self.cols[1].dot(v),
            self.cols[2].dot(v),
        )
    }

    /// True if every entry is finite.
    pub fn is_finite(&self) -> bool {
        self.cols.iter().all(|c| c.is_finite())
    }
}

impl Mul<Vec3> for Rotation {
    type Output = Vec3;
    fn mul(self, v: Vec3) -> Vec3 {
        self.cols[0] * v.x + self.cols[1] * v.y + self.cols[2] * v.z
    }
}

impl Mul for Rotation {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        Self::from_cols(self * o.cols[0], self * o.cols[1], self * o.cols[2])
    }
}
