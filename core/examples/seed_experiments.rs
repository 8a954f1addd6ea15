//! The seed thesis's simulation experiments (spec §8.2 E7–E9), printed next to the seed's
//! numbers.
//!
//! `cargo run --release -p armgate-core --example seed_experiments`
#![allow(missing_docs, clippy::unwrap_used)]

#[path = "../tests/common/mod.rs"]
mod common;

use common::experiments::{UNREACHABLE, rectangle_config, run_divergence, run_rectangle};

fn main() {
    let d = run_divergence(&common::robot("ranger-mk1"));
    println!("E7: ranger-mk1 sequence ending at the unreachable {UNREACHABLE:?} m");
    println!(
        "  seed without guard: chaotic motion near full extension; with guard: stops near the closest reachable pose, WN22 sent"
    );
    println!(
        "  ours: final tool {:.4?} m, {:.4} m from the goal; shoulder→tool {:.4} m of {:.4} m reach",
        d.final_position.as_slice(),
        d.final_distance,
        d.extension.0,
        d.extension.1
    );
    println!(
        "        moved away from the goal by {:.2e} m in all (largest single tick {:.2e} m); largest joint step {:.4} rad/tick; WN22 raised on {} ticks",
        d.total_retreat, d.worst_retreat, d.max_joint_step, d.divergence_ticks
    );
    println!();
    println!("E8/E9: rectangle (0.5,0.2,0.1)→(0.5,0.2,0.4)→(0.5,−0.2,0.4)→(0.5,−0.2,0.1)→back,");
    println!("v_max 0.05 m/s, a_max 0.10 m/s², constant tool orientation, ideal arm.\n");
    println!(
        "| exp | robot      | seed mean | seed max        | ours mean  | ours max   | at (s) | max joint step/tick | duration (s) |"
    );
    println!(
        "|-----|------------|-----------|-----------------|------------|------------|--------|---------------------|--------------|"
    );
    for (exp, robot, seed_mean, seed_max) in [
        ("E8", "hybrid", "0.18 mm", "2.02 mm (23 s)"),
        ("E9", "ranger-mk2", "≈ 1 µm", "8 µm (23 s)"),
    ] {
        let r = run_rectangle(&rectangle_config(common::robot(robot)));
        println!(
            "| {exp}  | {robot:<10} | {seed_mean:<9} | {seed_max:<15} | {:>8.2e} m | {:>8.2e} m | {:>6.2} | {:>19.5} | {:>12.2} |",
            r.mean_error, r.max_error, r.max_error_time, r.max_joint_step, r.duration
        );
        println!(
            "|     | tool rpy {:?}; joints start {:.4?} end {:.4?}; WN22 ticks {} |",
            r.rpy,
            &r.first_joints[..],
            &r.last_joints[..],
            r.divergence_ticks
        );
    }
}
