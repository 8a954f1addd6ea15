//! Rigid transforms (frames) and the displacement between two frames.

use core::ops::Mul;

use super::{Rotation, Vec3};

/// A rigid transform: the pose of a frame (rotation and origin) in a reference frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Frame {
    /// Orientation.
    pub rot: Rotation,
    /// Origin (m).
    pub pos: Vec3,
}

/// A 6-vector of linear and angular parts: a velocity twist, or a small displacement.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Twist {
    /// Linear part (m or m/s).
    pub linear: Vec3,
    /// Angular part (rad or rad/s), a rotation vector in the base frame.
    pub angular: Vec3,
}

impl Twist {
    /// The six components `[vx, vy, vz, wx, wy, wz]`.
    pub fn to_array(self) -> [f64; 6] {
        let [a, b, c] = self.linear.to_array();
        let [d, e, f] = self.angular.to_array();
        [a, b, c, d, e, f]
    }

    /// A twist from `[vx, vy, vz, wx, wy, wz]`.
    pub fn from_array(t: [f64; 6]) -> Self {
        let [a, b, c, d, e, f] = t;
        Self {
            linear: Vec3::new(a, b, c),
            angular: Vec3::new(d, e, f),
        }
    }
}

impl Frame {
    /// The identity transform.
    pub const IDENTITY: Self = Self {
        rot: Rotation::IDENTITY,
        pos: Vec3::ZERO,
    };

    /// A frame from a rotation and an origin.
    pub const fn new(rot: Rotation, pos: Vec3) -> Self {
        Self { rot, pos }
    }

    /// Craig's modified DH transform `RotX(alpha) · TransX(a) · RotZ(theta) · TransZ(d)`
    /// (KDL `Frame::DH_Craig1989(a, alpha, d, theta)`).
    pub fn dh(a: f64, alpha: f64, d: f64, theta: f64) -> Self {
        let (sa, ca) = libm::sincos(alpha);
        let (st, ct) = libm::sincos(theta);
        Self::new(
            Rotation::from_rows([
                [ct, -st, 0.0],
                [st * ca, ct * ca, -sa],
                [st * sa, ct * sa, ca],
            ]),
            Vec3::new(a, -sa * d, ca * d),
        )
    }

    /// The inverse transform.
    pub fn inverse(&self) -> Self {
        let rot = self.rot.transpose();
        Self::new(rot, -(rot * self.pos))
    }

    /// The displacement from `self` to `goal` in base coordinates: `(p_goal − p, rotvec)` where
    /// rotvec is the rotation vector of `R_goal · Rᵀ` (KDL `diff`, with a robust log map).
    pub fn diff(&self, goal: &Frame) -> Twist {
        Twist {
            linear: goal.pos - self.pos,
            angular: (goal.rot * self.rot.transpose()).rotation_vector(),
        }
    }

    /// The seed's mixed distance `|Δp| + |Δθ|` (m + rad, 1 m ≡ 1 rad).
    pub fn dist(&self, other: &Frame) -> f64 {
        let d = self.diff(other);
        d.linear.norm() + d.angular.norm()
    }

    /// True if every entry is finite.
    pub fn is_finite(&self) -> bool {
        self.rot.is_finite() && self.pos.is_finite()
    }
}

impl Mul for Frame {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        Self::new(self.rot * o.rot, self.rot * o.pos + self.pos)
    }
}
