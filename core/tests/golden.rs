//! The seed's golden vector (spec §2.4, thesis Fig. 3.3) on ranger-mk1.
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]
// The seed deployed rounded angles such as 1.5708; tests use them as the seed did.
#![allow(clippy::approx_constant)]

mod common;

use armgate_core::kinematics::Chain;
use armgate_core::math::{self, Quaternion};

#[test]
fn fig_3_3_pose_matches_the_seed_screenshot() {
    let chain = Chain::new(&common::robot("ranger-mk1"));
    let q = [-1.5838, 2.0360, 1.3499, -0.2471, 1.2428, -0.0595];
    let f = chain.forward(&q).unwrap();
    let quat = Quaternion::from_rotation(&f.rotation);
    let rpy = math::rpy(&f.rotation);
    let close = |got: &[f64], want: &[f64]| got.iter().zip(want).all(|(g, w)| (g - w).abs() < 2e-4);
    assert!(
        close(f.translation.vector.as_slice(), &[-0.0543, 0.5242, 0.2138]),
        "{:?}",
        f.translation.vector
    );
    assert!(
        close(&quat.to_array(), &[-0.5266, 0.4212, 0.5767, 0.4612]),
        "{quat:?}"
    );
    assert!(close(&rpy, &[-0.0007, 1.4801, 1.7917]), "{rpy:?}");
}

#[test]
fn home_pose_matches_the_spec() {
    let chain = Chain::new(&common::robot("ranger-mk1"));
    let f = chain
        .forward(&[1.5708, 0.0, 1.5708, 0.0, 1.5708, 0.0])
        .unwrap();
    let quat = Quaternion::from_rotation(&f.rotation).to_array();
    let want_p = [0.0, 0.0200, 0.6660];
    let want_q = [0.0, 0.0, -0.70711, 0.70711];
    assert!(
        f.translation
            .vector
            .iter()
            .zip(want_p)
            .all(|(g, w)| (g - w).abs() < 1e-4)
    );
    assert!(
        quat.iter().zip(want_q).all(|(g, w)| (g - w).abs() < 1e-4),
        "{quat:?}"
    );
}
