//! Tool poses as the protocol carries them.
//!
//! The arithmetic is nalgebra's; the protocol's own conventions — the quaternion's wire order
//! (x, y, z, w) and sign rule (w ≥ 0), the seed's roll/pitch/yaw extraction with its gimbal branch
//! (spec §2.4) — are the protocol crate's, shared with the controller.

use nalgebra::Rotation3;

pub use armgate_protocol::client::{Mode, Quaternion};

/// A tool pose: position (m) and orientation as a quaternion in wire order (x, y, z, w).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// x, y, z in metres.
    pub xyz: [f64; 3],
    /// The orientation, scalar last.
    pub quaternion: Quaternion,
}

impl Default for Pose {
    fn default() -> Self {
        Self {
            xyz: [0.0; 3],
            quaternion: Quaternion::IDENTITY,
        }
    }
}

impl Pose {
    /// A pose from a position and roll, pitch, yaw (rad; `R = Rz(yaw)·Ry(pitch)·Rx(roll)`,
    /// spec §2.4).
    pub fn from_xyz_rpy(xyz: [f64; 3], [roll, pitch, yaw]: [f64; 3]) -> Self {
        Self {
            xyz,
            // nalgebra's Euler angles are the same Rz(yaw)·Ry(pitch)·Rx(roll).
            quaternion: Quaternion::from_rotation(&Rotation3::from_euler_angles(roll, pitch, yaw)),
        }
    }

    /// The orientation as a rotation matrix (the quaternion normalised first, since the wire
    /// carries it as float32; a zero quaternion reads as the identity).
    pub fn rotation(&self) -> Rotation3<f64> {
        self.quaternion
            .normalized()
            .map_or_else(Rotation3::identity, Quaternion::to_rotation)
    }

    /// Roll, pitch, yaw (rad), extracted exactly as spec §2.4 says, including its gimbal branch
    /// (nalgebra's `euler_angles` treats gimbal lock differently).
    pub fn rpy(&self) -> [f64; 3] {
        armgate_protocol::client::rpy(&self.rotation())
    }

    /// The distance between the positions (m).
    pub fn distance(&self, other: &Self) -> f64 {
        let [a, b, c] = self.xyz;
        let [x, y, z] = other.xyz;
        ((a - x).powi(2) + (b - y).powi(2) + (c - z).powi(2)).sqrt()
    }

    /// The angle of the rotation between the orientations (rad, in [0, π]).
    pub fn angle_to(&self, other: &Self) -> f64 {
        self.rotation().angle_to(&other.rotation())
    }
}

/// The next mode in the teleop's cycle off → joint → Cartesian → off.
pub const fn next_mode(mode: Mode) -> Mode {
    match mode {
        Mode::Off => Mode::Joint,
        Mode::Joint => Mode::Cartesian,
        Mode::Cartesian => Mode::Off,
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use std::f64::consts::FRAC_PI_2;

    use super::*;

    /// The Fig. 3.3 quaternion of spec §2.4, to full precision (the spec prints 4 decimals).
    pub const GOLDEN_QUATERNION: Quaternion = Quaternion::new(
        -0.526634164654559,
        0.4211537127348358,
        0.5766734207798411,
        0.4612307151896264,
    );

    #[test]
    fn golden_vector_rpy() {
        // Spec §2.4: the Fig. 3.3 pose, RPY (−0.0007, 1.4801, 1.7917).
        let pose = Pose {
            xyz: [-0.0543, 0.5242, 0.2138],
            quaternion: GOLDEN_QUATERNION,
        };
        let [r, p, y] = pose.rpy();
        assert!((r - -0.0007).abs() < 1e-9, "{r}");
        assert!((p - 1.4801).abs() < 1e-9, "{p}");
        assert!((y - 1.7917).abs() < 1e-9, "{y}");
        // The 4-decimal quaternion printed in the spec gives the same angles to 2e-3 only:
        // at a pitch of 85° roll and yaw are ill-conditioned.
        let rounded = Pose {
            quaternion: Quaternion::new(-0.5266, 0.4212, 0.5767, 0.4612),
            ..pose
        };
        let [r, p, y] = rounded.rpy();
        assert!(
            (r - -0.0007).abs() < 2e-3 && (p - 1.4801).abs() < 1e-4 && (y - 1.7917).abs() < 2e-3
        );
    }

    #[test]
    fn gimbal_branch_puts_everything_into_roll() {
        let pose = Pose::from_xyz_rpy([0.0; 3], [0.3, FRAC_PI_2, 0.2]);
        let [r, p, y] = pose.rpy();
        assert!((p - FRAC_PI_2).abs() < 1e-9);
        assert_eq!(y, 0.0);
        // With pitch = +π/2 only roll − yaw is defined.
        assert!((r - 0.1).abs() < 1e-6, "{r}");
    }

    #[test]
    fn rpy_round_trips_away_from_gimbal_lock() {
        let pose = Pose::from_xyz_rpy([0.1, 0.2, 0.3], [0.1, -0.4, 2.0]);
        let [r, p, y] = pose.rpy();
        assert!((r - 0.1).abs() < 1e-9 && (p + 0.4).abs() < 1e-9 && (y - 2.0).abs() < 1e-9);
        assert!(pose.quaternion.w >= 0.0);
    }

    #[test]
    fn distances() {
        let a = Pose::from_xyz_rpy([0.0, 0.0, 0.0], [0.0; 3]);
        let b = Pose::from_xyz_rpy([0.0, 0.003, 0.004], [0.0, 0.0, 0.5]);
        assert!((a.distance(&b) - 0.005).abs() < 1e-12);
        assert!((a.angle_to(&b) - 0.5).abs() < 1e-9);
        assert!(a.angle_to(&a) < 1e-6);
    }

    #[test]
    fn quaternions_keep_the_wire_sign_rule() {
        // Half a turn about z: w = 0, so the sign follows z.
        let pose = Pose::from_xyz_rpy([0.0; 3], [0.0, 0.0, std::f64::consts::PI]);
        let q = pose.quaternion;
        assert!(q.w.abs() < 1e-15 && (q.z - 1.0).abs() < 1e-15, "{q:?}");
        // The negated quaternion is the same rotation; read back, it has the wire's sign.
        let flipped = Quaternion::new(-q.x, -q.y, -q.z, -q.w);
        assert!(Quaternion::from_rotation(&flipped.to_rotation()).z > 0.0);
        assert_eq!(Quaternion::new(0.0, 0.0, 0.0, 0.0).normalized(), None);
        assert_eq!(Quaternion::new(0.0, 0.0, 0.0, f64::NAN).normalized(), None);
        let scaled = Quaternion::new(0.0, 0.0, 1.2, 1.6).normalized().unwrap();
        assert_eq!(scaled, Quaternion::new(0.0, 0.0, 0.6, 0.8));
    }

    #[test]
    fn modes() {
        assert_eq!(Mode::from_value(1.9), Some(Mode::Cartesian));
        assert_eq!(Mode::from_value(3.0), None);
        assert_eq!(next_mode(Mode::Cartesian), Mode::Off);
    }
}
