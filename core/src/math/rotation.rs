//! The logarithm map of a rotation, robust where nalgebra's is not.

use nalgebra::{Rotation3, Vector3};

/// The rotation vector (axis × angle, angle in [0, π]) of `r`: the logarithm map, inverse of
/// `Rotation3::new`.
///
/// Robust for every rotation, including half turns, where the seed's KDL `GetRot` (and
/// nalgebra's `scaled_axis`) return zero (spec §9 item 4): near π the axis comes from the
/// symmetric part of the matrix. Exact to rounding for tiny angles, where the IK converges.
pub fn rotation_vector(r: &Rotation3<f64>) -> Vector3<f64> {
    let m = r.matrix();
    // v = sin θ · k
    let v = Vector3::new(m.m32 - m.m23, m.m13 - m.m31, m.m21 - m.m12) * 0.5;
    // max/min rather than `f64::clamp`, which has a panic path.
    #[allow(clippy::manual_clamp)]
    let c = ((m.m11 + m.m22 + m.m33 - 1.0) * 0.5).max(-1.0).min(1.0);
    let s2 = v.norm_squared();
    if s2 < 1e-6 && c > 0.0 {
        // θ/sin θ = asin(s)/s = 1 + s²/6 + 3s⁴/40 + …; the next term (≤ 5e-20) is below
        // rounding. Saves the square root and the atan2 on the IK's last iterations.
        return v * (1.0 + s2 / 6.0 + 0.075 * s2 * s2);
    }
    let s = crate::math::sqrt(s2);
    let theta = libm::atan2(s, c);
    if c > -0.5 {
        return v * (theta / s);
    }
    // θ > 120°: sin θ is small and inaccurate; use (R + Rᵀ)/2 − cI = (1 − c) k kᵀ.
    let one_c = 1.0 - c;
    let b = (m + m.transpose()) * 0.5;
    let (b00, b11, b22) = (b.m11 - c, b.m22 - c, b.m33 - c);
    let k = if b00 >= b11 && b00 >= b22 {
        let kx = crate::math::sqrt(b00 / one_c);
        Vector3::new(kx, b.m12 / (one_c * kx), b.m13 / (one_c * kx))
    } else if b11 >= b22 {
        let ky = crate::math::sqrt(b11 / one_c);
        Vector3::new(b.m21 / (one_c * ky), ky, b.m23 / (one_c * ky))
    } else {
        let kz = crate::math::sqrt(b22 / one_c);
        Vector3::new(b.m31 / (one_c * kz), b.m32 / (one_c * kz), kz)
    };
    let k = k * (1.0 / k.norm());
    let k = if k.dot(&v) < 0.0 { -k } else { k };
    k * theta
}
