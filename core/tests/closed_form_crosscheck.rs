//! Cases found by `tools/ik_crosscheck.py` (armgate's closed form against EAIK): known joint
//! vectors, within the shipped files' limits, that the closed form once got wrong.
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod common;

use armgate_core::kinematics::Chain;

/// How far the wrist sits from its singularity (axis 6 in line with axis 4), rad: the range
/// (1e-12, ~1e-6) where subproblem 2 once returned no root (its common point's γ² was taken
/// as a difference that rounding swamps, and its projection lengths compared as if unsquared).
const NEAR_SINGULAR: [f64; 5] = [1e-12, 1e-11, 1e-9, 1e-7, 1e-6];

/// How close the found configuration must be to `q`, rad. A wrist `d` from singular fixes θ4
/// and θ6 apart only to about 2e-16 / d (the pose moves by d per radian of their difference):
/// 2.7e-4 at d = 1e-12, where any value that close reproduces the pose within 1e-9.
const SAME_CONFIGURATION: f64 = 1e-3;

/// `q`'s configuration is among every solution of its own pose (reference `q`), and global IK
/// seeded at `q` stays there: a BG/GL goal at the arm's own pose must not move it to another
/// branch.
fn assert_kept(name: &str, q: &[f64; 6]) {
    let robot = common::robot(name);
    let chain = Chain::new(&robot);
    assert!(chain.within_limits(q), "{name}: {q:?}");
    let target = chain.forward(q).unwrap();
    let solutions = chain.solve_all(&target, q).unwrap();
    assert!(
        solutions.iter().any(|s| s
            .q
            .iter()
            .zip(q)
            .all(|(a, b)| (a - b).abs() < SAME_CONFIGURATION)),
        "{name}: {q:?} not among {solutions:?}"
    );
    let global = chain.solve_global(&target, q, &robot.ik, 1).unwrap();
    let moved = global
        .solution()
        .q
        .iter()
        .zip(q)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        moved < SAME_CONFIGURATION,
        "{name}: global IK from {q:?} moved {moved} rad"
    );
}

#[test]
fn ranger_mk1_wrist_near_singular_is_solved() {
    // θ5 near π: axes 4 and 6 in line (to the 7e-6 rad that the file's 1.5708 twists leave).
    // Before the fix: solve_all returned 1 solution (branch 3, shoulder flipped) instead of 3,
    // and global IK from q moved joint 1 by π.
    for d in NEAR_SINGULAR {
        assert_kept(
            "ranger-mk1",
            &[0.3, 1.0, 0.5, 0.7, core::f64::consts::PI - d, 0.4],
        );
    }
}

#[test]
fn puma560_wrist_near_singular_is_solved() {
    // θ5 near 0. Before the fix: solve_all returned 1 solution instead of 2; global IK from q
    // moved a joint by 2.2 rad.
    for d in NEAR_SINGULAR {
        assert_kept("puma560", &[0.3, -2.0, 0.5, 0.7, -d, 0.4]);
    }
}
