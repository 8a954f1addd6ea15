//! Orientation conventions and the geometry primitives (spec §2.4, §3.5, §9 item 4).
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]

use std::f64::consts::{FRAC_PI_2, PI};

use armgate_core::math::{self, Frame, Quaternion, Rotation3, Vector3};
use armgate_core::rng::SplitMix64;

fn assert_rot_close(a: &Rotation3<f64>, b: &Rotation3<f64>, tol: f64) {
    for (x, y) in a.matrix().iter().zip(b.matrix().iter()) {
        assert!((x - y).abs() < tol, "{a:?} != {b:?}");
    }
}

fn random_rotation(rng: &mut SplitMix64) -> Rotation3<f64> {
    let axis = Vector3::new(
        rng.uniform(-1.0, 1.0),
        rng.uniform(-1.0, 1.0),
        rng.uniform(-1.0, 1.0),
    );
    let axis = axis * (1.0 / axis.norm());
    Rotation3::new(axis * rng.uniform(0.0, PI))
}

#[test]
fn rpy_is_fixed_xyz_angles() {
    let (r, p, y) = (0.3, -0.4, 1.2);
    let composed = Rotation3::from_axis_angle(&Vector3::z_axis(), y)
        * Rotation3::from_axis_angle(&Vector3::y_axis(), p)
        * Rotation3::from_axis_angle(&Vector3::x_axis(), r);
    assert_rot_close(&Rotation3::from_euler_angles(r, p, y), &composed, 1e-15);
    let [r2, p2, y2] = math::rpy(&Rotation3::from_euler_angles(r, p, y));
    assert!((r2 - r).abs() < 1e-12 && (p2 - p).abs() < 1e-12 && (y2 - y).abs() < 1e-12);
}

#[test]
fn rpy_gimbal_lock_branch_sets_yaw_zero() {
    let rot = Rotation3::from_euler_angles(0.2, FRAC_PI_2, 0.5);
    let [roll, pitch, yaw] = math::rpy(&rot);
    assert_eq!(yaw, 0.0);
    assert!((pitch - FRAC_PI_2).abs() < 1e-12);
    assert_rot_close(&Rotation3::from_euler_angles(roll, pitch, yaw), &rot, 1e-9);
}

#[test]
fn quaternion_is_scalar_last_hamilton() {
    // 90° about z: (0, 0, sin 45°, cos 45°)
    let q = Quaternion::from_rotation(&Rotation3::from_axis_angle(&Vector3::z_axis(), FRAC_PI_2));
    let h = std::f64::consts::FRAC_1_SQRT_2;
    assert!((q.z - h).abs() < 1e-15 && (q.w - h).abs() < 1e-15);
    assert_rot_close(
        &q.to_rotation(),
        &Rotation3::from_axis_angle(&Vector3::z_axis(), FRAC_PI_2),
        1e-15,
    );
}

#[test]
fn quaternion_round_trip_keeps_w_non_negative() {
    let mut rng = SplitMix64::new(7);
    for _ in 0..1000 {
        let r = random_rotation(&mut rng);
        let q = Quaternion::from_rotation(&r);
        assert!(q.w >= 0.0);
        assert!((q.to_array().iter().map(|v| v * v).sum::<f64>() - 1.0).abs() < 1e-12);
        assert_rot_close(&q.to_rotation(), &r, 1e-12);
    }
}

#[test]
fn half_turns_in_the_xy_plane_have_finite_quaternions() {
    // The seed's PS path divided by zero here (spec §9 item 4).
    for axis in [
        Vector3::x(),
        Vector3::y(),
        Vector3::new(1.0, 1.0, 0.0) * (1.0 / 2f64.sqrt()),
    ] {
        let r = Rotation3::new(axis * PI);
        let q = Quaternion::from_rotation(&r);
        assert!(q.to_array().iter().all(|v| v.is_finite()));
        assert!(q.w.abs() < 1e-12);
        assert!((q.vector() - axis).norm() < 1e-12 || (q.vector() + axis).norm() < 1e-12);
        assert_rot_close(&q.to_rotation(), &r, 1e-12);
    }
}

#[test]
fn log_map_inverts_exp_map_up_to_half_turn() {
    let mut rng = SplitMix64::new(11);
    let angles = [0.0, 1e-9, 1e-4, 0.5, 2.0, 3.0, PI - 1e-6, PI];
    for &angle in &angles {
        for _ in 0..200 {
            let axis = random_rotation(&mut rng) * Vector3::x();
            let v = axis * angle;
            let r = Rotation3::new(v);
            let back = math::rotation_vector(&r);
            if angle < PI - 1e-3 {
                assert!((back - v).norm() < 1e-9, "angle {angle}: {back:?} vs {v:?}");
            } else {
                // At π the axis sign is arbitrary; the rotation must match.
                assert!((back.norm() - angle).abs() < 1e-9);
                assert_rot_close(&Rotation3::new(back), &r, 1e-9);
            }
        }
    }
}

#[test]
fn diff_of_a_half_turn_is_not_zero() {
    // The seed's KDL GetRot returned ~0 for an error of exactly π (spec §3.5).
    let a = Frame::identity();
    let b = Frame::from_parts(
        Vector3::zeros().into(),
        Rotation3::from_axis_angle(&Vector3::x_axis(), PI),
    );
    assert!((math::diff(&a, &b).fixed_rows::<3>(3).norm() - PI).abs() < 1e-12);
    assert!((math::dist(&a, &b) - PI).abs() < 1e-12);
}

#[test]
fn dh_matches_its_factorisation() {
    let (a, alpha, d, theta) = (0.3, -0.7, 0.25, 1.1);
    let product = Frame::from_parts(
        Vector3::zeros().into(),
        Rotation3::from_axis_angle(&Vector3::x_axis(), alpha),
    ) * Frame::from_parts(Vector3::new(a, 0.0, 0.0).into(), Rotation3::identity())
        * Frame::from_parts(
            Vector3::zeros().into(),
            Rotation3::from_axis_angle(&Vector3::z_axis(), theta),
        )
        * Frame::from_parts(Vector3::new(0.0, 0.0, d).into(), Rotation3::identity());
    let dh = math::dh(a, alpha, d, theta);
    assert_rot_close(&dh.rotation, &product.rotation, 1e-15);
    assert!((dh.translation.vector - product.translation.vector).norm() < 1e-15);
}

#[test]
fn frame_inverse_composes_to_identity() {
    let f = Frame::from_parts(
        Vector3::new(1.0, -2.0, 0.5).into(),
        Rotation3::from_euler_angles(0.1, 0.2, 0.3),
    );
    let i = f * f.inverse();
    assert_rot_close(&i.rotation, &Rotation3::identity(), 1e-15);
    assert!(i.translation.vector.norm() < 1e-15);
}

#[test]
fn zero_and_non_finite_quaternions_do_not_normalise() {
    assert!(Quaternion::new(0.0, 0.0, 0.0, 0.0).normalized().is_none());
    assert!(
        Quaternion::new(f64::NAN, 0.0, 0.0, 1.0)
            .normalized()
            .is_none()
    );
    assert!(
        Quaternion::new(f64::INFINITY, 0.0, 0.0, 1.0)
            .normalized()
            .is_none()
    );
    let q = Quaternion::new(0.0, 0.0, 2.0, 0.0).normalized().unwrap();
    assert_eq!(q.to_array(), [0.0, 0.0, 1.0, 0.0]);
}
