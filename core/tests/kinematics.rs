//! FK, Jacobian, IK and velocity IK on every shipped robot.
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]
// The seed deployed rounded angles such as 1.5708; tests use them as the seed did.
#![allow(clippy::approx_constant)]

mod common;

use armgate_core::MAX_JOINTS;
use armgate_core::config::IkConfig;
use armgate_core::kinematics::{Chain, IkError, IkResult, KinematicsError, diverges};
use armgate_core::math::{self, Frame, Rotation3, SVector, Twist, Vector3};
use armgate_core::rng::SplitMix64;

#[test]
fn jacobian_matches_finite_differences() {
    let mut rng = SplitMix64::new(1);
    for (name, config) in common::all_robots() {
        let chain = Chain::new(&config);
        for _ in 0..20 {
            let q = chain.random_joints(&mut rng);
            let j = chain.jacobian(&q).unwrap();
            let f0 = chain.forward(&q).unwrap();
            let h = 1e-7;
            for i in 0..chain.dof() {
                let mut qh = q;
                qh[i] += h;
                let d = math::diff(&f0, &chain.forward(&qh).unwrap());
                let numeric = d / h;
                let analytic = j.column(i);
                for (a, b) in analytic.iter().zip(numeric.iter()) {
                    assert!(
                        (a - b).abs() < 1e-5,
                        "{name} joint {i}: {analytic:?} vs {numeric:?}"
                    );
                }
            }
        }
    }
}

#[test]
fn link_frames_end_at_the_tool() {
    let mut rng = SplitMix64::new(2);
    for (name, config) in common::all_robots() {
        let chain = Chain::new(&config);
        let q = chain.random_joints(&mut rng);
        let mut links = [Frame::identity(); MAX_JOINTS];
        let tool = chain.link_frames(&q, &mut links).unwrap();
        assert_eq!(tool, chain.forward(&q).unwrap(), "{name}");
        // Frame {i} is the DH product of the first i joints.
        let last = links[chain.dof() - 1];
        let t = &config.tool;
        let tool_offset = math::dh(t.a, t.alpha, t.d, t.theta)
            * Frame::from_parts(
                Vector3::from(t.xyz).into(),
                Rotation3::from_euler_angles(t.rpy[0], t.rpy[1], t.rpy[2]),
            );
        let rebuilt = last * tool_offset;
        assert!(
            (rebuilt.translation.vector - tool.translation.vector).norm() < 1e-12,
            "{name}"
        );
    }
}

#[test]
fn tracking_ik_round_trips_within_limits() {
    for (name, config) in common::all_robots() {
        // Draws of its own per robot: adding a robot file changes no other robot's cases.
        let mut rng = SplitMix64::new(3);
        let chain = Chain::new(&config);
        let mut converged = 0;
        let trials = 300;
        for _ in 0..trials {
            let q = chain.random_joints(&mut rng);
            let target = chain.forward(&q).unwrap();
            let seed: Vec<f64> = q.iter().map(|v| v + rng.uniform(-0.1, 0.1)).collect();
            let result = chain.solve_tracking(&target, &seed, &config.ik).unwrap();
            let s = result.solution();
            assert!(chain.within_limits(&s.q), "{name}: {:?}", s.q);
            if let IkResult::Converged(s) = result {
                converged += 1;
                let reached = math::diff(&chain.forward(&s.q).unwrap(), &target);
                assert!(
                    reached.fixed_rows::<3>(0).norm() < 1e-9
                        && reached.fixed_rows::<3>(3).norm() < 1e-9,
                    "{name}"
                );
                // The closed form reports the error of FK on the sines and cosines it solved
                // for, which FK on the values reproduces up to rounding.
                assert!((s.position_error - reached.fixed_rows::<3>(0).norm()).abs() < 1e-14);
            }
        }
        assert!(converged >= trials - 1, "{name}: {converged}/{trials}");
    }
}

#[test]
fn global_ik_round_trips_from_mid_range() {
    let mut rng = SplitMix64::new(4);
    for (name, config) in common::all_robots() {
        let chain = Chain::new(&config);
        let mid = chain.mid_range();
        let trials = 200;
        let mut converged = 0;
        for k in 0..trials {
            let q = chain.random_joints(&mut rng);
            let target = chain.forward(&q).unwrap();
            let result = chain.solve_global(&target, &mid, &config.ik, k).unwrap();
            assert!(chain.within_limits(&result.solution().q), "{name}");
            converged += usize::from(result.is_converged());
        }
        assert!(converged >= 197, "{name}: {converged}/{trials}");
    }
}

#[test]
fn global_ik_is_deterministic() {
    let config = common::robot("ranger-mk1");
    let chain = Chain::new(&config);
    let target = chain.forward(&[0.3, 1.2, -0.5, 0.4, 2.0, -1.0]).unwrap();
    let a = chain
        .solve_global(&target, &chain.mid_range(), &config.ik, 42)
        .unwrap();
    let b = chain
        .solve_global(&target, &chain.mid_range(), &config.ik, 42)
        .unwrap();
    assert_eq!(a, b);
}

#[test]
fn unreachable_target_reports_best_effort_within_budget() {
    let config = common::robot("ranger-mk1");
    let chain = Chain::new(&config);
    let target = Frame::from_parts(Vector3::new(-0.5, 4.0, 0.7).into(), Rotation3::identity());
    let ik = IkConfig {
        global_iterations: 300,
        ..config.ik
    };
    match chain
        .solve_global(&target, &chain.mid_range(), &ik, 1)
        .unwrap()
    {
        IkResult::NotConverged(s) => {
            assert!(s.iterations <= 300);
            assert!(chain.within_limits(&s.q));
            // Reach is about 1.5 m, the target is 4 m out.
            assert!(s.position_error > 2.0 && s.position_error.is_finite());
        }
        IkResult::Converged(_) => panic!("an unreachable target converged"),
    }
    let tracked = chain
        .solve_tracking(&target, &chain.mid_range(), &config.ik)
        .unwrap();
    assert!(!tracked.is_converged());
    assert!(chain.within_limits(&tracked.solution().q));
}

#[test]
fn redundant_arm_tracks_a_singular_target() {
    // ranger-mk2 fully stretched along z (q = 0) is singular; targets there must not blow up.
    let config = common::robot("ranger-mk2");
    let chain = Chain::new(&config);
    let zero = vec![0.0; chain.dof()];
    let target = chain.forward(&zero).unwrap();
    let seed: Vec<f64> = (0..chain.dof()).map(|i| 0.05 * (i as f64 - 3.5)).collect();
    let r = chain.solve_tracking(&target, &seed, &config.ik).unwrap();
    let s = r.solution();
    assert!(s.q.iter().all(|v| v.is_finite()));
    assert!(s.position_error < 1e-6, "{s:?}");
}

#[test]
fn nan_inf_and_huge_inputs_are_errors_not_panics() {
    let config = common::robot("ranger-mk1");
    let chain = Chain::new(&config);
    let good = [1.5708, 0.0, 1.5708, 0.0, 1.5708, 0.0];
    let target = chain.forward(&good).unwrap();
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let mut q = good;
        q[2] = bad;
        assert_eq!(chain.forward(&q), Err(KinematicsError::NonFiniteJoints));
        assert_eq!(
            chain.solve_tracking(&target, &q, &config.ik),
            Err(IkError::NonFiniteSeed)
        );
        let mut t = target;
        t.translation.vector.y = bad;
        assert_eq!(
            chain.solve_global(&t, &good, &config.ik, 0),
            Err(IkError::NonFiniteTarget)
        );
        assert!(
            chain
                .joint_rates(&q, &Twist::default(), 0.01, None)
                .is_err()
        );
    }
    assert_eq!(
        chain.forward(&good[..5]),
        Err(KinematicsError::WrongJointCount)
    );
    assert_eq!(
        chain.solve_tracking(&target, &[0.0; 7], &config.ik),
        Err(IkError::WrongJointCount)
    );
    // Huge but finite: far outside the limits and the workspace.
    let huge = [1e300, -1e300, 1e300, 1e300, -1e300, 1e300];
    assert!(chain.forward(&huge).is_ok());
    let far = Frame::from_parts(
        Vector3::new(1e300, -1e300, 1e300).into(),
        Rotation3::identity(),
    );
    let r = chain.solve_global(&far, &huge, &config.ik, 0).unwrap();
    assert!(!r.is_converged() && chain.within_limits(&r.solution().q));
    let r = chain.solve_tracking(&far, &huge, &config.ik).unwrap();
    assert!(!r.is_converged() && chain.within_limits(&r.solution().q));
}

#[test]
fn divergence_guard_rejects_only_worse_solutions() {
    let target = Frame::from_parts(Vector3::new(1.0, 0.0, 0.0).into(), Rotation3::identity());
    let current = Frame::from_parts(Vector3::new(0.9, 0.0, 0.0).into(), Rotation3::identity());
    let better = Frame::from_parts(Vector3::new(0.95, 0.0, 0.0).into(), Rotation3::identity());
    let slightly_worse = Frame::from_parts(
        Vector3::new(0.89995, 0.0, 0.0).into(),
        Rotation3::identity(),
    );
    let worse = Frame::from_parts(
        Vector3::new(0.9, 0.0, 0.0).into(),
        Rotation3::from_axis_angle(&Vector3::z_axis(), 0.01),
    );
    assert!(!diverges(&target, &better, &current, 1e-4));
    assert!(!diverges(&target, &slightly_worse, &current, 1e-4));
    assert!(diverges(&target, &worse, &current, 1e-4));
}

#[test]
fn joint_rates_reproduce_the_twist() {
    let mut rng = SplitMix64::new(5);
    for (name, config) in common::all_robots() {
        let chain = Chain::new(&config);
        for _ in 0..20 {
            let q = chain.random_joints(&mut rng);
            let j = chain.jacobian(&q).unwrap();
            if chain.manipulability(&q).unwrap() < 1e-3 || chain.dof() < 6 {
                continue;
            }
            let twist = Twist::new(0.01, -0.02, 0.005, 0.02, 0.0, -0.01);
            let rates = chain.joint_rates(&q, &twist, 0.0, None).unwrap();
            let got = j * SVector::from(*rates.as_array());
            for (g, w) in got.iter().zip(twist.iter()) {
                assert!((g - w).abs() < 1e-6, "{name}: {got:?}");
            }
            // A null-space preference changes the joint rates, not the twist.
            let pull: Vec<f64> = (0..chain.dof()).map(|i| 0.1 * (i as f64 - 2.0)).collect();
            let biased = chain.joint_rates(&q, &twist, 0.0, Some(&pull)).unwrap();
            let got = j * SVector::from(*biased.as_array());
            for (g, w) in got.iter().zip(twist.iter()) {
                assert!((g - w).abs() < 1e-6, "{name}: {got:?}");
            }
            if chain.dof() > 6 {
                assert!(
                    biased
                        .iter()
                        .zip(rates.iter())
                        .any(|(a, b)| (a - b).abs() > 1e-6)
                );
            }
        }
    }
}

#[test]
fn manipulability_vanishes_at_a_singularity() {
    let chain = Chain::new(&common::robot("ranger-mk1"));
    // Wrist pitch at π (joint 5 limits allow it): axes 4 and 6 align.
    let singular = [0.3, 1.0, -0.5, 0.2, std::f64::consts::PI, 0.1];
    let regular = [0.3, 1.0, -0.5, 0.2, 2.0, 0.1];
    assert!(chain.manipulability(&singular).unwrap() < 1e-9);
    assert!(chain.manipulability(&regular).unwrap() > 1e-3);
}

/// FK of every shipped robot against fixtures computed independently with KDL (PyKDL's
/// `ChainFkSolverPos_recursive`; `tools/fk_fixtures.py` regenerates them).
#[test]
fn fk_matches_kdl_fixtures() {
    for (name, config) in common::all_robots() {
        let chain = Chain::new(&config);
        let path = common::robots_dir().join(format!("../core/tests/fixtures/fk_{name}.csv"));
        let text =
            std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let mut rows = 0;
        for line in text.lines().skip(1) {
            let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
            let n = chain.dof();
            assert_eq!(v.len(), n + 12, "{name}: {line}");
            let f = chain.forward(&v[..n]).unwrap();
            let want_p = &v[n..n + 3];
            let want_r = &v[n + 3..];
            for (got, want) in f.translation.vector.iter().zip(want_p) {
                assert!(
                    (got - want).abs() < 1e-12,
                    "{name} position at {:?}",
                    &v[..n]
                );
            }
            let rows_got: Vec<f64> = f.rotation.matrix().transpose().iter().copied().collect();
            for (got, want) in rows_got.iter().zip(want_r) {
                assert!(
                    (got - want).abs() < 1e-12,
                    "{name} rotation at {:?}",
                    &v[..n]
                );
            }
            rows += 1;
        }
        assert!(rows >= 23, "{name}: only {rows} fixture rows");
    }
}
