//! The seed's simulation experiments (spec §8.2) with our goals asserted.
//! `cargo run --release -p armgate-core --example seed_experiments` prints the table.
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod common;

use common::experiments::{rectangle_config, run_divergence, run_rectangle};

#[test]
fn e8_hybrid_rectangle_has_micrometre_kinematic_error() {
    let run = run_rectangle(&rectangle_config(common::robot("hybrid")));
    // Seed: mean 0.18 mm, max 2.02 mm. Goal: mean ≤ 0.01 mm, max ≤ 0.1 mm.
    assert!(run.mean_error <= 0.01e-3, "{run:?}");
    assert!(run.max_error <= 0.1e-3, "{run:?}");
    assert_eq!(run.divergence_ticks, 0);
    // Continuous joint paths: at 0.05 m/s no joint moves more than 2 mm or 0.02 rad per tick.
    assert!(run.max_joint_step < 0.02, "{run:?}");
}

#[test]
fn e9_ranger_mk2_rectangle_within_a_micrometre() {
    let run = run_rectangle(&rectangle_config(common::robot("ranger-mk2")));
    // Seed: ≈ 1 µm mean, 8 µm max. Goal: ≤ 1 µm mean, ≤ 2 µm max.
    assert!(run.mean_error <= 1e-6, "{run:?}");
    assert!(run.max_error <= 2e-6, "{run:?}");
    assert!(run.max_joint_step < 0.02, "{run:?}");
}

#[test]
fn e7_unreachable_goal_stops_the_arm_near_the_boundary_and_warns() {
    let run = run_divergence(&common::robot("ranger-mk1"));
    assert!(run.divergence_ticks > 0, "no WN22");
    assert_eq!(run.total_retreat, 0.0, "moved away from the goal: {run:?}");
    let (extension, reach) = run.extension;
    assert!(extension > 0.95 * reach && extension <= reach, "{run:?}");
    // Joint steps stay within the rate limit (0.2 rad/s × 19.44 ms).
    assert!(run.max_joint_step <= 0.2 * 0.01944 + 1e-12, "{run:?}");
}
