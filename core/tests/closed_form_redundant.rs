//! Closed-form IK of the redundant arms (iiwa14: 7 joints, ranger-mk2: 8) beyond what
//! `closed_form.rs` checks for every family: the singular configurations of a spherical
//! shoulder (the arm stretched along axis 1, the elbow stretched, the wrist's axes in line, and
//! pairs of them), and global IK finding a value of the redundancy parameters (θ3, and θ5 on
//! eight joints) with a solution when the seed's have none.
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod common;

use armgate_core::kinematics::{CHECK, Chain, Joints, Solutions};
use armgate_core::math::{self, Frame};
use armgate_core::rng::SplitMix64;

const REDUNDANT: [&str; 2] = ["iiwa14", "ranger-mk2"];

fn chain(name: &str) -> Chain {
    Chain::new(&common::robot(name))
}

/// The redundancy parameters of a chain: θ3, and θ5 on eight joints.
fn parameters(chain: &Chain) -> &'static [usize] {
    if chain.dof() == 8 { &[2, 4] } else { &[2] }
}

fn same_modulo_turns(a: &[f64], b: &[f64], tol: f64) -> bool {
    a.iter().zip(b).all(|(x, y)| {
        let d = x - y;
        (d - core::f64::consts::TAU * (d / core::f64::consts::TAU).round()).abs() <= tol
    })
}

/// Every solution reproduces `target` within CHECK, lies within the limits, keeps the
/// reference's redundancy parameters, and the branches are distinct.
fn assert_exact(chain: &Chain, target: &Frame, reference: &[f64], solutions: &Solutions) {
    for (i, s) in solutions.iter().enumerate() {
        let e = math::diff(&chain.forward(&s.q).unwrap(), target);
        assert!(e.fixed_rows::<3>(0).norm() <= CHECK, "position {e:?}");
        assert!(e.fixed_rows::<3>(3).norm() <= CHECK, "orientation {e:?}");
        assert!(chain.within_limits(&s.q), "{:?}", s.q);
        for &p in parameters(chain) {
            assert!((s.q[p] - reference[p]).abs() <= 1e-6, "parameter {p} kept");
        }
        for other in solutions.iter().take(i) {
            assert_ne!(other.branch, s.branch, "branch twice");
        }
    }
}

/// `q` is among the solutions of its own pose for its own redundancy values (the other
/// joints' reference is `others`), and on the branch `branch_of` reports.
fn assert_recovered(chain: &Chain, q: &Joints, others: &[f64], tol: f64, what: &str) {
    let target = chain.forward(q).unwrap();
    let mut reference = Joints::from_slice(others).unwrap();
    for &p in parameters(chain) {
        reference[p] = q[p];
    }
    let solutions = chain.solve_all(&target, &reference).unwrap();
    assert_exact(chain, &target, &reference, &solutions);
    assert!(
        solutions.iter().any(|s| same_modulo_turns(&s.q, q, tol)),
        "{what}: {q:?} not among {solutions:?}"
    );
}

#[test]
fn the_stretched_arm_and_its_singular_configurations_are_solved() {
    let mut rng = SplitMix64::new(7);
    for name in REDUNDANT {
        let chain = chain(name);
        let n = chain.dof();
        // The zero configuration: on iiwa14 the arm straight up, every other axis in line.
        let zero = Joints::zeros(n);
        assert_recovered(&chain, &zero, &zero, 1e-7, &format!("{name} zero"));
        // The elbow stretched (θ4 = 0 on both), the wrist stretched (its middle solved joint
        // at 0), and the shoulder stretched (θ2 = 0) with either.
        for k in 0..200 {
            let mut q = chain.random_joints(&mut rng);
            let pick = rng.next_f64();
            if pick < 0.4 {
                q[3] = 0.0;
            }
            if (0.2..0.6).contains(&pick) {
                q[n - 2] = 0.0;
            }
            if pick > 0.5 {
                q[1] = 0.0;
            }
            // A tangent root (the stretched elbow) is known to √ε ≈ 1.5e-8; near the arm
            // stretched along axis 1 (θ2 → 0) θ1 and the wrist amplify that by ~1/|θ2|, so
            // at θ2 = 0.003 the configuration is only known to ~5e-6 (its pose to 1e-9).
            assert_recovered(&chain, &q, &q, 2e-5, &format!("{name} singular #{k}"));
        }
    }
}

#[test]
fn global_ik_and_the_nearest_solution_use_the_closed_form() {
    let mut rng = SplitMix64::new(0x61);
    for name in REDUNDANT {
        let config = common::robot(name);
        let chain = Chain::new(&config);
        for k in 0..500 {
            let q = chain.random_joints(&mut rng);
            let target = chain.forward(&q).unwrap();
            // From the configuration itself: that very solution, on the branch branch_of reports.
            let nearest = chain.solve_nearest(&target, &q, None).unwrap().unwrap();
            assert!(same_modulo_turns(&nearest.q, &q, 1e-7), "{name} #{k}");
            assert_eq!(chain.branch_of(&q), Some(nearest.branch), "{name} #{k}");
            // From the middle of the ranges: some exact solution, whatever θ3 it needs.
            common::assert_global_ik_exact(&chain, &config.ik, &target, k, &format!("{name} #{k}"));
        }
    }
}
