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
use armgate_core::math::{Frame, Rotation, Vec3};
use armgate_core::rng::SplitMix64;

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
    let mut placed = plain.clone();
    placed.base.xyz = [0.1, -0.2, 0.3];
    placed.base.rpy = [0.01, -0.02, 0.5];
    let base = Frame::new(
        Rotation::from_rpy(0.01, -0.02, 0.5),
        Vec3::new(0.1, -0.2, 0.3),
    );
    let (a, b) = (Chain::new(&plain), Chain::new(&placed));
    let mut rng = SplitMix64::new(7);
    for _ in 0..20 {
        let q = common::random_q(&a, &mut rng);
        let expected = base * a.forward(&q).unwrap();
        assert!(b.forward(&q).unwrap().dist(&expected) < 1e-12);
    }
}

#[test]
fn beta_turns_about_y_after_a() {
    let mut config = common::robot("ranger-mk1");
    config.joints[2].beta = 0.02;
    let chain = Chain::new(&config);
    let mut rng = SplitMix64::new(8);
    for _ in 0..20 {
        let q = common::random_q(&chain, &mut rng);
        let mut expected = Frame::IDENTITY;
        for (j, qi) in config.joints.iter().zip(&q) {
            let x = Frame::new(Rotation::rot_x(j.alpha), Vec3::new(j.a, 0.0, 0.0));
            let y = Frame::new(Rotation::rot_y(j.beta), Vec3::ZERO);
            expected = expected * x * y * Frame::dh(0.0, 0.0, j.d, j.theta + qi);
        }
        let t = &config.tool;
        expected = expected * Frame::dh(t.a, t.alpha, t.d, t.theta);
        assert!(chain.forward(&q).unwrap().dist(&expected) < 1e-12);
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
