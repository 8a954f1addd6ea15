//! Blended via points (issue 13 part 2): tolerance 0 is today's behaviour bit for bit; with a
//! tolerance the path passes each via point within it, without stopping, with continuous
//! velocity and within the limits.
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod common;

use armgate_core::config::ValidRobot;
use armgate_core::kinematics::Joints;
use armgate_core::motion::{Controller, IdealArm, Mode};
use common::experiments::{rectangle_config, run_rectangle};

/// FNV-1a over the bits of every value: a fingerprint of a whole set-point trace.
fn fingerprint(values: impl IntoIterator<Item = f64>) -> u64 {
    values.into_iter().fold(0xcbf2_9ce4_8422_2325, |h, v| {
        v.to_bits()
            .to_le_bytes()
            .iter()
            .fold(h, |h, b| (h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3))
    })
}

const MK1_READY: [f64; 6] = [1.5708, 0.6, -0.4, 0.2, 1.8, 0.1];

/// A joint sequence of four points on ranger-mk1 with an ideal arm: every joint command.
fn joint_sequence_commands(config: &ValidRobot) -> Vec<Joints> {
    let mut ctrl = Controller::new(config);
    let mut arm = IdealArm::new(Joints::from_slice(&MK1_READY).unwrap());
    let period = config.control_period;
    let mut now = 0.0;
    ctrl.step(now, &arm.measured()).unwrap();
    ctrl.set_mode(Mode::Joint).unwrap();
    for k in 0..4 {
        let mut q = MK1_READY;
        q[0] += if k % 2 == 0 { 0.3 } else { -0.1 } * (k + 1) as f64;
        q[2] -= 0.2 * (k + 1) as f64;
        q[4] += 0.1 * k as f64;
        ctrl.set_joint_via(k, &q, if k == 2 { 3.0 } else { 0.0 })
            .unwrap();
    }
    ctrl.start_joint_sequence().unwrap();
    let mut commands = Vec::new();
    for _ in 0..100_000 {
        now += period;
        let out = ctrl.step(now, &arm.measured()).unwrap();
        arm.step(out.command.as_ref());
        commands.extend(out.command);
        if out.events.sequence_finished || out.events.sequence_aborted {
            assert!(out.events.sequence_finished);
            return commands;
        }
    }
    panic!("the joint sequence did not finish");
}

/// Fingerprints of the set-points before blending existed (commit 1ca5d57): a sequence with
/// tolerance 0 must reproduce them bit for bit.
const E8_FINGERPRINT: u64 = 0x0685_2839_ae0c_3735;
const JOINT_FINGERPRINT: u64 = 0xe5fb_8be0_c917_ff8d;

#[test]
fn tolerance_zero_reproduces_the_unblended_set_points_bit_for_bit() {
    let e8 = run_rectangle(&rectangle_config(common::robot("hybrid")));
    let e8_print = fingerprint(
        e8.trace
            .iter()
            .flat_map(|t| t.tool.iter().copied().collect::<Vec<_>>()),
    );
    let joints = joint_sequence_commands(&common::robot("ranger-mk1"));
    let joint_print = fingerprint(
        joints
            .iter()
            .flat_map(|q| q.iter().copied().collect::<Vec<_>>()),
    );
    println!(
        "E8 {e8_print:#x} ({} ticks), joints {joint_print:#x} ({} ticks)",
        e8.trace.len(),
        joints.len()
    );
    assert_eq!(e8_print, E8_FINGERPRINT);
    assert_eq!(joint_print, JOINT_FINGERPRINT);
}
