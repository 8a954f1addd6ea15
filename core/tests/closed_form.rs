//! Closed-form IK: family detection on every shipped robot, and every solution exact, within
//! the limits and complete (the configuration a target came from is among its solutions),
//! including round angles and singular configurations.
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod common;

use armgate_core::kinematics::{Branch, CHECK, Chain, Family, IkError, Joints, Solutions};
use armgate_core::math::{self, Frame};
use armgate_core::rng::SplitMix64;

const CLOSED: [(&str, Family); 8] = [
    ("ranger-mk1", Family::SphericalWrist),
    ("ranger-mk1-table21", Family::SphericalWrist),
    ("ranger-mk1-jerk", Family::SphericalWrist),
    ("puma560", Family::SphericalWrist),
    ("ur5", Family::ThreeParallel),
    ("iiwa14", Family::SphericalShoulder),
    ("ranger-mk2", Family::SphericalShoulder),
    ("hybrid", Family::PrismaticBase),
];

fn chain(name: &str) -> Chain {
    Chain::new(&common::robot(name))
}

/// Equal joint by joint up to whole turns, within `tol`.
fn same_modulo_turns(a: &[f64], b: &[f64], tol: f64) -> bool {
    a.iter().zip(b).all(|(x, y)| {
        let d = x - y;
        (d - core::f64::consts::TAU * (d / core::f64::consts::TAU).round()).abs() <= tol
    })
}

/// Every solution reproduces `target` within CHECK, lies within the limits, and the branches
/// are distinct.
fn assert_exact(chain: &Chain, target: &Frame, solutions: &Solutions, what: &str) {
    for (i, s) in solutions.iter().enumerate() {
        let e = math::diff(&chain.forward(&s.q).unwrap(), target);
        assert!(
            e.fixed_rows::<3>(0).norm() <= CHECK,
            "{what}: position {e:?}"
        );
        assert!(
            e.fixed_rows::<3>(3).norm() <= CHECK,
            "{what}: orientation {e:?}"
        );
        assert!(chain.within_limits(&s.q), "{what}: {:?}", s.q);
        for other in solutions.iter().take(i) {
            assert_ne!(other.branch, s.branch, "{what}: branch twice");
        }
    }
}

/// The redundancy parameters of a chain (docs/kinematics.md): θ3, and θ5 on eight joints.
fn parameters(chain: &Chain) -> &'static [usize] {
    match (chain.family().family, chain.dof()) {
        (Family::SphericalShoulder, 8) => &[2, 4],
        (Family::SphericalShoulder, _) => &[2],
        _ => &[],
    }
}

/// `q` is among the solutions of its own pose (a redundant arm's for `q`'s own redundancy
/// parameters, the other joints' reference `reference`).
fn assert_recovered(chain: &Chain, q: &Joints, reference: &[f64], tol: f64, what: &str) {
    let target = chain.forward(q).unwrap();
    let mut reference = Joints::from_slice(reference).unwrap();
    for &p in parameters(chain) {
        reference[p] = q[p];
    }
    let solutions = chain.solve_all(&target, &reference).unwrap();
    for s in &solutions {
        for &p in parameters(chain) {
            assert!((s.q[p] - q[p]).abs() <= 1e-6, "{what}: parameter {p} kept");
        }
    }
    assert_exact(chain, &target, &solutions, what);
    assert!(
        solutions.iter().any(|s| same_modulo_turns(&s.q, q, tol)),
        "{what}: {q:?} not among {solutions:?}"
    );
}

#[test]
fn the_family_of_every_shipped_robot_is_detected() {
    for (name, family) in CLOSED {
        let fit = chain(name).family();
        assert_eq!(fit.family, family, "{name}");
        assert!(fit.is_exact(), "{name}: {fit:?}");
    }
    // Prismatic joints anywhere but the first two: no closed form here (docs/kinematics.md).
    let moved = common::robot("hybrid")
        .edit(|c| c.joints.swap(1, 2))
        .unwrap();
    let moved = Chain::new(&moved);
    assert_eq!(moved.family().family, Family::Numeric);
    let target = moved.forward(&moved.mid_range()).unwrap();
    assert_eq!(
        moved.solve_all(&target, &moved.mid_range()),
        Err(IkError::NoClosedForm)
    );
}

#[test]
fn random_configurations_are_among_the_solutions_of_their_pose() {
    let mut rng = SplitMix64::new(0x26);
    for (name, _) in CLOSED {
        let chain = chain(name);
        let mut counts = [0usize; 9];
        for k in 0..2000 {
            let q = chain.random_joints(&mut rng);
            assert_recovered(
                &chain,
                &q,
                &chain.mid_range(),
                1e-7,
                &format!("{name} #{k}"),
            );
            let target = chain.forward(&q).unwrap();
            counts[chain.solve_all(&target, &q).unwrap().len()] += 1;
        }
        // Most poses have several admissible solutions.
        assert!(
            counts[2..].iter().sum::<usize>() > 1000,
            "{name}: {counts:?}"
        );
    }
}

#[test]
fn round_angles_and_singular_configurations_are_solved() {
    let quarter = core::f64::consts::FRAC_PI_2;
    let mut rng = SplitMix64::new(5);
    for (name, family) in CLOSED {
        let chain = chain(name);
        // Multiples of π/2 within the limits (where a joint has none, its middle).
        for k in 0..200 {
            let mut q = chain.random_joints(&mut rng);
            for (i, v) in q.iter_mut().enumerate() {
                let round = (*v / quarter).round() * quarter;
                let (lo, hi) = (chain.min()[i], chain.max()[i]);
                if lo <= round && round <= hi && rng.next_f64() < 0.8 {
                    *v = round;
                }
            }
            // A singular wrist leaves a joint free: it keeps the reference's value. A
            // redundant arm at θ2 = 0 (axes 1 and 3 in line) has its two shoulder roots meet:
            // a tangency, whose root is known to ~3e-7 rad.
            let tol = if parameters(&chain).is_empty() {
                1e-7
            } else {
                1e-6
            };
            assert_recovered(&chain, &q, &q, tol, &format!("{name} round #{k}"));
        }
        if family == Family::PrismaticBase {
            // Its singular configurations: `a_prismatic_base_at_its_singular_configurations`.
            continue;
        }
        // The wrist singularity, θ5 = 0 or π: axes 4 and 6 in line (spherical wrist), axis 6
        // parallel to the three parallel axes (ur5).
        for k in 0..50 {
            let mut q = chain.random_joints(&mut rng);
            q[4] = 0.0;
            if !chain.within_limits(&q) {
                q[4] = core::f64::consts::PI;
            }
            if !chain.within_limits(&q) {
                continue;
            }
            assert_recovered(&chain, &q, &q, 1e-7, &format!("{name} wrist #{k}"));
        }
        // The stretched elbow: θ3 where axis 2's point is farthest from the wrist.
        let stretched = stretched_elbow(&chain);
        for k in 0..50 {
            let mut q = chain.random_joints(&mut rng);
            q[2] = stretched;
            // Away from the wrist singularity (θ5 = 0 or π on all three), which the loop
            // above covers: both at once leave θ4 and θ6 defined only to ~1e-5.
            if chain.within_limits(&q) && q[4].sin().abs() > 0.1 {
                assert_recovered(
                    &chain,
                    &q,
                    &chain.mid_range(),
                    1e-6,
                    &format!("{name} elbow #{k}"),
                );
            }
        }
    }
}

/// The θ3 (within the limits, mod 2π) at which the origin of frame 4 is farthest from that of
/// frame 2: the elbow stretched out.
fn stretched_elbow(chain: &Chain) -> f64 {
    let reach = |q3: f64| {
        let mut q = chain.mid_range();
        q[2] = q3;
        let mut links = [Frame::identity(); armgate_core::MAX_JOINTS];
        chain.link_frames(&q, &mut links).unwrap();
        (links[3].translation.vector - links[1].translation.vector).norm()
    };
    let steps = 3600;
    let (lo, hi) = (-core::f64::consts::PI, core::f64::consts::PI);
    let mut best = lo;
    for i in 0..steps {
        let x = lo + (hi - lo) * f64::from(i) / f64::from(steps);
        if reach(x) > reach(best) {
            best = x;
        }
    }
    // Golden-section refinement around the grid's best.
    let (mut a, mut b) = (best - 0.01, best + 0.01);
    for _ in 0..100 {
        let (c, d) = (b - 0.618 * (b - a), a + 0.618 * (b - a));
        if reach(c) > reach(d) {
            b = d;
        } else {
            a = c;
        }
    }
    let x = 0.5 * (a + b);
    let (lo, hi) = (chain.min()[2], chain.max()[2]);
    [x, x - core::f64::consts::TAU, x + core::f64::consts::TAU]
        .into_iter()
        .find(|v| lo <= *v && *v <= hi)
        .unwrap_or(x)
}

/// `pose` with its position and roll, pitch, yaw rounded to `f32`, as a request carries it.
fn in_f32(pose: &Frame) -> Frame {
    let [r, p, y] = math::rpy(&pose.rotation).map(|v| f64::from(v as f32));
    let t = pose.translation.vector.map(|v| f64::from(v as f32));
    Frame::from_parts(t.into(), math::Rotation3::from_euler_angles(r, p, y))
}

/// hybrid's singular configurations: axis 6 along axis 3 (θ4 + θ5 = 0 or π, the zero pose
/// among them), where only θ3 ± θ6 is fixed and θ3 keeps the reference's value; the arm
/// vertical (θ4 = ±π/2), where θ4's two roots meet; and both at once.
#[test]
fn a_prismatic_base_at_its_singular_configurations() {
    let chain = chain("hybrid");
    let zero = Joints::zeros(6);
    assert_recovered(&chain, &zero, &zero, 1e-7, "zero");
    let half = core::f64::consts::FRAC_PI_2;
    let mut rng = SplitMix64::new(0x4b);
    for k in 0..300 {
        let mut q = chain.random_joints(&mut rng);
        let pick = rng.next_f64();
        if pick > 0.4 {
            q[3] = if rng.next_f64() < 0.5 { half } else { -half };
        }
        if pick < 0.6 {
            // θ5 = −θ4 (φ = 0) or π − θ4 (φ = π), wrapped into ±π.
            let phi = if pick < 0.3 {
                0.0
            } else {
                core::f64::consts::PI
            };
            q[4] = libm::remainder(phi - q[3], core::f64::consts::TAU);
        }
        assert!(chain.within_limits(&q));
        // The tangent root of θ4 is known to √ε ≈ 1.5e-8 before Newton's polish.
        let what = format!("hybrid singular #{k}");
        assert_recovered(&chain, &q, &q, 1e-6, &what);
        // The pose as the wire carries it (f32): ~1e-7 off the singular one, so θ3 is no longer
        // free but set by the rounding's direction, and the slides follow the turned arm (up
        // to 1 m: admissible from within ±1 m); still solved, exactly. (Rounded off the
        // vertical arm, the height may lie beyond the reach: no exact solution.)
        if pick < 0.4 && q[0].abs() < 1.0 && q[1].abs() < 1.0 {
            let rounded = in_f32(&chain.forward(&q).unwrap());
            let solutions = chain.solve_all(&rounded, &q).unwrap();
            assert!(!solutions.is_empty(), "{what}: rounded");
            assert_exact(&chain, &rounded, &solutions, &what);
        }
        // Away from θ3's freedom the nearest solution is found from mid-range too.
        if pick >= 0.6 {
            assert_recovered(&chain, &q, &chain.mid_range(), 1e-6, "hybrid vertical");
        }
    }
}

/// Global IK from the middle of the ranges takes an exact solution, without a Newton step,
/// on every six-joint closed-form robot (the redundant arms' sweep of their parameters:
/// closed_form_redundant.rs).
#[test]
fn global_ik_takes_an_exact_solution() {
    let mut rng = SplitMix64::new(0x6b);
    for (name, family) in CLOSED {
        if family == Family::SphericalShoulder {
            continue;
        }
        let config = common::robot(name);
        let chain = Chain::new(&config);
        for k in 0..500 {
            let target = chain.forward(&chain.random_joints(&mut rng)).unwrap();
            common::assert_global_ik_exact(&chain, &config.ik, &target, k, &format!("{name} #{k}"));
        }
    }
}

#[test]
fn the_nearest_solution_and_a_chosen_branch() {
    let mut rng = SplitMix64::new(9);
    for (name, _) in CLOSED {
        let chain = chain(name);
        for _ in 0..200 {
            let q = chain.random_joints(&mut rng);
            let target = chain.forward(&q).unwrap();
            let nearest = chain.solve_nearest(&target, &q, None).unwrap().unwrap();
            assert!(same_modulo_turns(&nearest.q, &q, 1e-7), "{name}");
            assert_eq!(chain.branch_of(&q), Some(nearest.branch));
            for s in chain.solve_all(&target, &q).unwrap() {
                let chosen = chain.solve_nearest(&target, &q, Some(s.branch)).unwrap();
                assert_eq!(chosen.map(|c| c.branch), Some(s.branch));
            }
        }
        assert_eq!(Branch::from_bits(8), None);
    }
}

#[test]
fn unreachable_and_hostile_targets_have_no_solution() {
    for (name, _) in CLOSED {
        let chain = chain(name);
        let far = Frame::translation(5.0, 0.0, 0.0);
        assert!(
            chain
                .solve_all(&far, &chain.mid_range())
                .unwrap()
                .is_empty(),
            "{name}"
        );
        let nan = Frame::translation(f64::NAN, 0.0, 0.0);
        assert_eq!(
            chain.solve_all(&nan, &chain.mid_range()),
            Err(IkError::NonFiniteTarget)
        );
        assert_eq!(
            chain.solve_all(&far, &[0.0; 3]),
            Err(IkError::WrongJointCount)
        );
    }
}

/// Away from the singularities near which the ideal model's angles differ from the true
/// chain's by ~deviation / sin: the wrist's (θ5 = 0 or π) on six revolute joints; on hybrid
/// axis 6 along axis 3 (θ4 + θ5 = 0 or π) and the arm vertical (θ4 = ±π/2). There Newton
/// from the ideal model's root may find another branch.
fn regular(family: Family, q: &Joints) -> bool {
    match family {
        Family::PrismaticBase => (q[3] + q[4]).sin().abs() > 0.1 && q[3].cos().abs() > 0.1,
        _ => q[4].sin().abs() > 0.1,
    }
}

/// A calibrated arm: twists, lengths and offsets fitted a little off their nominal values, a
/// Hayati β between the parallel axes (on joint `tilted`), the base placed. It is only near
/// its family, so the ideal model's solutions are polished on the true chain: every
/// configuration is still recovered, and global IK succeeds as on the nominal file.
#[test]
fn a_calibrated_arm_is_solved_through_its_ideal_model() {
    for (name, family, tilted) in [
        ("ranger-mk1", Family::SphericalWrist, 2),
        ("puma560", Family::SphericalWrist, 2),
        ("ur5", Family::ThreeParallel, 2),
        ("hybrid", Family::PrismaticBase, 4),
    ] {
        let config = common::robot(name)
            .edit(|c| {
                c.base.xyz = [0.002, -0.001, 0.003];
                c.base.rpy = [0.001, -0.002, 0.0005];
                for (i, j) in c.joints.iter_mut().enumerate() {
                    let s = [1.0, -0.7, 0.4, -1.1, 0.8, -0.3][i];
                    j.alpha += 1e-3 * s;
                    j.a += 5e-4 * s;
                    j.d -= 4e-4 * s;
                    j.theta += 2e-3 * s;
                }
                c.joints[tilted].beta = 1.5e-3;
            })
            .unwrap();
        let chain = Chain::new(&config);
        let fit = chain.family();
        assert_eq!(fit.family, family, "{name}");
        assert!(!fit.is_exact() && fit.deviation < 1e-2, "{name}: {fit:?}");
        let mut rng = SplitMix64::new(0xca1);
        let mut global = 0;
        for k in 0..500 {
            let q = chain.random_joints(&mut rng);
            if regular(family, &q) {
                // Newton stops at 1e-10 m + rad: near a stretched elbow that leaves ~1e-6 rad.
                let what = format!("{name} #{k}");
                assert_recovered(&chain, &q, &chain.mid_range(), 1e-5, &what);
            }
            let target = chain.forward(&q).unwrap();
            let result = chain
                .solve_global(&target, &chain.mid_range(), &config.ik, k)
                .unwrap();
            global +=
                usize::from(result.is_converged() && chain.within_limits(&result.solution().q));
        }
        assert_eq!(global, 500, "{name}");
    }
}
