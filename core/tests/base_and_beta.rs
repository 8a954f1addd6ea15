//! The robot file's `[base]` frame and per-joint Hayati `beta`, which kinematic calibration
//! writes: absent they change nothing; present, FK is `Base · … RotX·TransX·RotY(β)·RotZ·TransZ …`.
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod common;

use armgate_core::config::parse_toml;
use armgate_core::kinematics::Chain;
use armgate_core::math::{self, Frame};
use armgate_core::rng::SplitMix64;
use nalgebra::{Rotation3, Vector3};

#[test]
fn absent_base_and_beta_are_zero() {
    let config = common::robot("ur5");
    assert_eq!(config.base.xyz, [0.0; 3]);
    assert_eq!(config.base.rpy, [0.0; 3]);
    assert!(config.joints.iter().all(|j| j.beta == 0.0));
}

#[test]
fn the_base_frame_moves_every_pose() {
    let plain = common::robot("ranger-mk1");
    let placed = plain
        .clone()
        .edit(|c| {
            c.base.xyz = [0.1, -0.2, 0.3];
            c.base.rpy = [0.01, -0.02, 0.5];
        })
        .unwrap();
    let base = Frame::from_parts(
        Vector3::new(0.1, -0.2, 0.3).into(),
        Rotation3::from_euler_angles(0.01, -0.02, 0.5),
    );
    let (a, b) = (Chain::new(&plain), Chain::new(&placed));
    let mut rng = SplitMix64::new(7);
    for _ in 0..20 {
        let q = a.random_joints(&mut rng);
        let expected = base * a.forward(&q).unwrap();
        assert!(math::dist(&b.forward(&q).unwrap(), &expected) < 1e-12);
    }
}

#[test]
fn beta_turns_about_y_after_a() {
    let config = common::robot("ranger-mk1")
        .edit(|c| c.joints[2].beta = 0.02)
        .unwrap();
    let chain = Chain::new(&config);
    let mut rng = SplitMix64::new(8);
    for _ in 0..20 {
        let q = chain.random_joints(&mut rng);
        let mut expected = Frame::identity();
        for (j, qi) in config.joints.iter().zip(q.iter()) {
            let x = Frame::from_parts(
                Vector3::new(j.a, 0.0, 0.0).into(),
                Rotation3::from_euler_angles(j.alpha, 0.0, 0.0),
            );
            let y = Frame::from_parts(
                Vector3::zeros().into(),
                Rotation3::from_euler_angles(0.0, j.beta, 0.0),
            );
            expected = expected * x * y * math::dh(0.0, 0.0, j.d, j.theta + qi);
        }
        let t = &config.tool;
        expected *= math::dh(t.a, t.alpha, t.d, t.theta);
        assert!(math::dist(&chain.forward(&q).unwrap(), &expected) < 1e-12);
    }
}

#[test]
fn base_and_beta_load_from_toml() {
    let text = std::fs::read_to_string(common::robots_dir().join("ur5.toml")).unwrap();
    let text = text.replace(
        "d = 0.089159\ntheta = 0.0\n",
        "d = 0.089159\ntheta = 0.0\nbeta = 0.001\n",
    ) + "\n[base]\nxyz = [0.5, 0.0, 0.0]\nrpy = [0.0, 0.0, 0.1]\n";
    let config = parse_toml(&text).unwrap();
    assert_eq!(config.base.xyz, [0.5, 0.0, 0.0]);
    assert_eq!(config.base.rpy, [0.0, 0.0, 0.1]);
    assert_eq!(config.joints[0].beta, 0.001);
    let bad = text.replace("beta = 0.001", "beta = nan");
    assert!(parse_toml(&bad).is_err());
}
