//! Issue 25's acceptance: a laser tracker 1.5–2 m from the robot, turned 30–40° about z and
//! tilted about 1°, measures 50 random poses of an arm with typical errors (0.05 mm noise). The
//! calibration must keep the robot in its own frame: every fitted constant close to the truth
//! expressed in the robot's base frame, the instrument's frame found on its own, the held-out
//! poses predicted through it, the workspace guarding the same place — and one gross error in
//! the data must change none of that.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)] // helpers of tests: a panic is a failed test

use armgate_calibrate::calibration::{Calibration, Options, Validation, calibrate};
use armgate_calibrate::fit::Measurement;
use armgate_calibrate::instrument::xyz_rpy;
use armgate_calibrate::measurements::{format, parse};
use armgate_calibrate::model::{FitSet, Geometry, MeasuredIn, Param};
use armgate_calibrate::{identify, plan, sim, world};
use armgate_core::config::{JointConfig, ValidRobot, load_file};
use armgate_core::kinematics::Chain;
use armgate_core::rng::SplitMix64;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

const NOISE: f64 = 0.05e-3;
const DEG: f64 = std::f64::consts::PI / 180.0;

fn robot(name: &str) -> ValidRobot {
    load_file(format!(
        "{}/../robots/{name}.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}

/// A tracker placement in the robot's base frame: 1.5–2 m away, 30–40° yaw, 0.7–1.2° tilt.
fn tracker(seed: u64) -> Isometry3<f64> {
    let mut rng = SplitMix64::new(seed);
    let (distance, azimuth) = (rng.uniform(1.5, 2.0), rng.uniform(0.0, 360.0) * DEG);
    let height = rng.uniform(-0.3, 0.3);
    let horizontal = (distance * distance - height * height).sqrt();
    let sign = |rng: &mut SplitMix64| if rng.next_f64() < 0.5 { -1.0 } else { 1.0 };
    let yaw = sign(&mut rng) * rng.uniform(30.0, 40.0) * DEG;
    let tilt = rng.uniform(0.7, 1.2) * DEG;
    let tilt_direction = rng.uniform(0.0, 360.0) * DEG;
    Isometry3::from_parts(
        Translation3::new(
            horizontal * azimuth.cos(),
            horizontal * azimuth.sin(),
            height,
        ),
        UnitQuaternion::from_euler_angles(
            tilt * tilt_direction.cos(),
            tilt * tilt_direction.sin(),
            yaw,
        ),
    )
}

/// Joint 1's constant transform `RotX(α)·TransX(a)·RotY(β)·RotZ(θ)·TransZ(d)` (revolute).
fn first_link(j: &JointConfig) -> Isometry3<f64> {
    Isometry3::rotation(Vector3::x() * j.alpha)
        * Isometry3::translation(j.a, 0.0, 0.0)
        * Isometry3::rotation(Vector3::y() * j.beta)
        * Isometry3::rotation(Vector3::z() * j.theta)
        * Isometry3::translation(0.0, 0.0, j.d)
}

/// The true arm in the robot's own frame — its base frame is where joint 1's nominal constants
/// put it — and the tracker's placement in that frame. Joint 1's errors (and the base's, which
/// the measurements never see) are the tracker's placement, not the robot's.
fn own_frame(
    truth: &ValidRobot,
    nominal: &ValidRobot,
    placement: &Isometry3<f64>,
) -> (ValidRobot, Isometry3<f64>) {
    let (t1, n1) = (truth.joints[0].clone(), nominal.joints[0].clone());
    let own = truth
        .clone()
        .edit(|c| {
            let j = &mut c.joints[0];
            (j.alpha, j.a, j.beta, j.theta, j.d) = (n1.alpha, n1.a, n1.beta, n1.theta, n1.d);
            c.base = nominal.base;
        })
        .unwrap();
    (own, first_link(&n1) * first_link(&t1).inverse() * placement)
}

/// Where the tool of `config` is at `q` in the frame of an instrument at `placement` (in the
/// robot's base frame), by the core's forward kinematics.
fn seen(config: &ValidRobot, placement: &Isometry3<f64>, q: &[f64]) -> Vector3<f64> {
    let base = Isometry3::from_parts(
        Translation3::from(Vector3::from(config.base.xyz)),
        UnitQuaternion::from_euler_angles(
            config.base.rpy[0],
            config.base.rpy[1],
            config.base.rpy[2],
        ),
    );
    let world = Chain::new(config).forward(q).unwrap().translation.vector;
    ((base * placement).inverse() * Point3::from(world)).coords
}

/// The calibrated robot file (the library's geometry written into the nominal one).
fn calibrated(nominal: &ValidRobot, result: &Calibration) -> ValidRobot {
    nominal
        .clone()
        .edit(|c| result.fit.geometry.apply_to(c))
        .unwrap()
}

struct Scenario {
    /// True if only the identifiable constants (and joint 1's and the base's) have errors:
    /// then the truth in the robot's own frame is exactly what the fit estimates.
    identifiable_errors: bool,
    nominal: ValidRobot,
    own: ValidRobot,
    placement: Isometry3<f64>,
    measured: Vec<Measurement>,
    check_poses: Vec<Vec<f64>>,
}

/// The tracker scenario; with `identifiable_errors`, the errors of constants that the poses
/// cannot tell from others' (J3.d beside J2.d, the wrist's beside the tool's) are left out —
/// those of joint 1 and the base stay in: they are the frame question.
fn scenario(name: &str, seed: u64, identifiable_errors: bool) -> Scenario {
    let nominal = robot(name);
    let mut truth = sim::perturb(&nominal, &sim::Errors::TYPICAL, seed).unwrap();
    let injected = tracker(seed);
    let poses = plan::random_poses(&nominal, 50, seed + 1).unwrap();
    if identifiable_errors {
        let g = Geometry::new(&nominal);
        let analysis = identify::analyse(
            &g,
            &g.candidates(FitSet::All, MeasuredIn::Instrument),
            &poses,
        );
        let mut t = Geometry::new(&truth);
        let joint_1 = [Param::Theta(0), Param::D(0), Param::A(0), Param::Alpha(0)];
        for p in analysis
            .unidentifiable
            .iter()
            .filter(|p| !joint_1.contains(p))
        {
            t.set(*p, g.get(*p));
        }
        truth = truth.edit(|c| t.apply_to(c)).unwrap();
    }
    let measured = sim::measure_from(&truth, &injected, &poses, NOISE, seed + 2);
    // Through the file format, so that measurements carry their line numbers.
    let measured = parse(&format(&measured, nominal.dof()), nominal.dof()).unwrap();
    let check_poses = plan::random_poses(&nominal, 100, seed + 3).unwrap();
    let (own, placement) = own_frame(&truth, &nominal, &injected);
    for q in &check_poses {
        let diff = seen(&truth, &injected, q) - seen(&own, &placement, q);
        assert!(diff.norm() < 1e-12, "the own-frame truth is the truth");
    }
    Scenario {
        identifiable_errors,
        nominal,
        own,
        placement,
        measured,
        check_poses,
    }
}

fn poses(measured: &[Measurement]) -> Vec<Vec<f64>> {
    measured.iter().map(|m| m.q.clone()).collect()
}

/// Calibrates and asserts every figure of the issue but the 3σ; returns the result and the
/// worst robot parameter's distance from the truth in σ.
fn check(name: &str, s: &Scenario, measured: &[Measurement]) -> (Calibration, f64) {
    let held_out = sim::measure_from(&s.own, &s.placement, &s.check_poses, 0.0, 0);
    let result = calibrate(
        &s.nominal,
        measured,
        &held_out,
        &Options::with_noise(Some(NOISE)),
    )
    .unwrap();
    println!("{name}:\n{}", result.report());
    assert!(result.problems().is_empty(), "{:?}", result.problems());
    // Errors of 0.5° and 1 mm are no modelling errors. (With errors in every constant, one that
    // absorbs a fixed partner's may move further: ur5's J5.theta takes J6.a's error at 0.7° per
    // mm on its 82 mm wrist.)
    if s.identifiable_errors {
        assert!(
            result.large_moves().is_empty(),
            "{name}: {:?}",
            result.large_moves()
        );
    }

    // The robot's own frame: joint 1's constants and the base stay nominal, and every fitted
    // constant is the truth's within 2 mm / 0.2° and 3σ (its σ floored at 1 µm / 0.1 mdeg for
    // the parameters the redundancies tie to a fixed partner by less).
    let g = &result.fit.geometry;
    let joint_1 = [Param::Theta(0), Param::D(0), Param::A(0), Param::Alpha(0)];
    for p in joint_1 {
        assert_eq!(g.get(p), result.nominal.get(p), "{p} moved");
    }
    assert_eq!(g.base(), Isometry3::identity());
    // With errors in identifiable constants only, the truth is the injected one. Otherwise a
    // constant whose partner is fixed (J2.d beside J3.d, J5.theta beside J6.a) absorbs the
    // partner's error: the truth it estimates is the noise-free fit at the same poses (which
    // reproduces the arm to well below the noise).
    let exact_data = sim::measure_from(&s.own, &s.placement, &poses(measured), 0.0, 0);
    let exact = calibrate(&s.nominal, &exact_data, &[], &Options::with_noise(None)).unwrap();
    assert!(exact.after.max < 0.025e-3, "{}", exact.after.max);
    let truth = if s.identifiable_errors {
        Geometry::new(&s.own)
    } else {
        exact.fit.geometry.clone()
    };
    // (The instrument's parameters are corrections to a registration: its placement is
    // compared below.)
    let mut worst: (Option<Param>, f64) = (None, 0.0);
    let robot_params = result.fit.params.iter().zip(&result.fit.std_dev);
    for (p, sd) in robot_params.filter(|(p, _)| !p.is_instrument()) {
        let error = (g.get(*p) - truth.get(*p)).abs();
        let tolerance = if p.is_angle() { 0.2 * DEG } else { 2e-3 };
        assert!(error <= tolerance, "{name}: {p} off the truth by {error:e}");
        let sigmas = error / sd;
        if sigmas > worst.1 {
            worst = (Some(*p), sigmas);
        }
    }

    // The instrument: where it is in the robot's own frame, to within 0.1 mm / 0.01° and (in
    // the worst σ-distance) 3σ.
    let fitted = result.instrument;
    let sigma = fitted.sigma.unwrap();
    let (truth_at, fitted_at) = (xyz_rpy(&s.placement), xyz_rpy(&fitted.pose));
    for k in 0..6 {
        let error = (truth_at[k] - fitted_at[k]).abs();
        assert!(
            error < if k < 3 { 0.1e-3 } else { 0.01 * DEG },
            "{name}: instrument {k}"
        );
        if error / sigma[k] > worst.1 {
            worst = (Some(Param::Instrument(k)), error / sigma[k]);
        }
    }
    println!("{name}: worst parameter {:?} at {:.2}σ", worst.0, worst.1);

    // Held-out poses through the reported instrument frame and the calibrated file, by the
    // core's forward kinematics.
    let file = calibrated(&s.nominal, &result);
    let distances: Vec<f64> = s
        .check_poses
        .iter()
        .map(|q| (seen(&file, &fitted.pose, q) - seen(&s.own, &s.placement, q)).norm())
        .collect();
    let mean = distances.iter().sum::<f64>() / distances.len() as f64;
    let max = distances.iter().copied().fold(0.0, f64::max);
    println!(
        "{name}: held-out {:.4} mm mean, {:.4} mm max",
        mean * 1e3,
        max * 1e3
    );
    assert!(mean <= 0.10e-3 && max <= 0.30e-3);
    let Validation::HeldOut { after, .. } = result.validation else {
        panic!("held-out poses were given")
    };
    assert!(
        (after.mean - mean).abs() < 1e-9,
        "the report's figure is the same"
    );

    // The workspace: unchanged, and its points are the same physical points as before (the
    // robot's base frame did not move).
    assert_eq!(file.workspace, s.nominal.workspace);
    let bounds = s.nominal.workspace.bounds;
    let corners = s.nominal.workspace.boxes.iter().chain([&bounds]);
    for b in corners {
        let point = Point3::new(b[1], b[3], b[5]);
        let before = s.placement.inverse() * point;
        let after = fitted.pose.inverse() * point;
        assert!(
            (before - after).norm() < 0.1e-3,
            "{name}: a workspace corner moved {:e} m",
            (before - after).norm()
        );
    }
    (result, worst.1)
}

/// The scenario with and without a gross error, and with errors in every constant; the worst
/// parameter's σ-distance of the three.
fn tracker_scenario(name: &str, seed: u64) -> f64 {
    let all = scenario(name, seed, false);
    let (_, every_constant) = check(name, &all, &all.measured);
    let s = scenario(name, seed, true);
    let (_, clean) = check(name, &s, &s.measured);

    // One gross error: a coordinate off by 0.5 m. The same figures, and the line is named.
    let mut spoiled = s.measured.clone();
    spoiled[17].position.x += 0.5;
    let (result, worst) = check(name, &s, &spoiled);
    assert_eq!(result.rejected.len(), 1, "{:?}", result.rejected);
    assert_eq!(
        result.rejected[0].name,
        format!("line {}", spoiled[17].line)
    );
    assert!(result.rejected[0].residual > 0.4);
    assert!(
        result
            .report()
            .contains(&format!("line {}: residual", spoiled[17].line))
    );
    every_constant.max(clean).max(worst)
}

#[test]
fn ranger_mk1_in_its_own_frame() {
    assert!(tracker_scenario("ranger-mk1", 31) <= 3.0);
}

#[test]
fn ur5_in_its_own_frame() {
    assert!(tracker_scenario("ur5", 34) <= 3.0);
}

#[test]
fn iiwa14_in_its_own_frame() {
    assert!(tracker_scenario("iiwa14", 33) <= 3.0);
}

/// 20 seeds per arm (`cargo test -p armgate-calibrate --test tracker -- --ignored
/// --nocapture`): every figure but the 3σ must hold for every seed. With 19–23 parameters, a
/// seed with one beyond 3σ is expected by chance now and then; beyond 4.5σ it is not.
#[test]
#[ignore]
fn many_seeds() {
    let (mut beyond_3, mut worst) = (0, 0.0_f64);
    for seed in 200..220 {
        for name in ["ranger-mk1", "ur5", "iiwa14"] {
            let sigmas = tracker_scenario(name, seed);
            if sigmas > 3.0 {
                beyond_3 += 1;
                eprintln!("{name} seed {seed}: a parameter at {sigmas:.2}σ");
            }
            worst = worst.max(sigmas);
        }
    }
    eprintln!(
        "60 scenarios (each clean and with a gross error): {beyond_3} with a parameter beyond 3σ, the worst {worst:.2}σ"
    );
    assert!(worst < 4.5);
}

#[test]
fn a_world_base_carries_the_workspace() {
    // ranger-mk1's column box, carried into a tracker's frame: the centre maps to the same
    // physical point, every corner stays inside (the carried box encloses the old one), and
    // the carried bounds lie inside the old ones.
    let nominal = robot("ranger-mk1");
    let to_tracker = tracker(7).inverse();
    let carried = world::carry(&nominal.workspace, &to_tracker);
    assert!(!carried.exact);
    let inside = |b: &[f64; 6], p: &Point3<f64>| {
        let tol = 1e-12;
        (b[0] - tol..=b[1] + tol).contains(&p.x)
            && (b[2] - tol..=b[3] + tol).contains(&p.y)
            && (b[4] - tol..=b[5] + tol).contains(&p.z)
    };
    let corners = |b: &[f64; 6]| -> Vec<Point3<f64>> {
        (0..8)
            .map(|k| Point3::new(b[k & 1], b[2 + (k >> 1 & 1)], b[4 + (k >> 2 & 1)]))
            .collect()
    };
    let (old, new) = (nominal.workspace.boxes[0], carried.workspace.boxes[0]);
    for c in corners(&old) {
        assert!(inside(&new, &(to_tracker * c)));
    }
    let centre = |b: &[f64; 6]| Point3::new(b[0] + b[1], b[2] + b[3], b[4] + b[5]) / 2.0;
    assert!((to_tracker * centre(&old) - centre(&new)).norm() < 1e-12);
    let back = to_tracker.inverse();
    for c in corners(&carried.workspace.bounds) {
        assert!(inside(&nominal.workspace.bounds, &(back * c)));
    }
    // Turned mostly about z, the bounds keep nearly all their height.
    let height = |b: &[f64; 6]| b[5] - b[4];
    let kept = height(&carried.workspace.bounds) / height(&nominal.workspace.bounds);
    assert!(kept > 0.9, "{kept}");
    // A quarter turn is exact both ways.
    let quarter = Isometry3::new(Vector3::new(1.0, 2.0, 3.0), Vector3::z() * 90.0 * DEG);
    let exact = world::carry(&nominal.workspace, &quarter);
    assert!(exact.exact);
    let b = exact.workspace.boxes[0];
    assert!(
        (b[0] - 0.8).abs() < 1e-12 && (b[1] - 1.2).abs() < 1e-12,
        "{b:?}"
    );
}

#[test]
fn a_wrong_file_is_reported_as_a_modelling_error() {
    // The arm is ranger-mk1, the file says its upper arm is 8 mm longer: the fit finds it, and
    // the report says that is a modelling error, not a calibration.
    let truth = robot("ranger-mk1");
    let wrong = truth.clone().edit(|c| c.joints[2].a += 8e-3).unwrap();
    let poses = plan::random_poses(&truth, 50, 5).unwrap();
    let measured = sim::measure_from(&truth, &tracker(5), &poses, NOISE, 6);
    let result = calibrate(&wrong, &measured, &[], &Options::with_noise(Some(NOISE))).unwrap();
    let moves = result.large_moves();
    assert_eq!(moves.len(), 1, "{moves:?}");
    assert_eq!(moves[0].0, Param::A(2));
    assert!((moves[0].1 + 8e-3).abs() < 0.05e-3);
    assert!(result.report().contains("WARNING: J3.a moved -8.0"));
    assert!(result.problems().is_empty());
}

#[test]
fn a_plan_identifies_the_instruments_frame_too() {
    // Six more parameters: the instrument's frame; joint 1's four constants are its.
    let planned = plan::plan(
        &robot("ur5"),
        FitSet::All,
        MeasuredIn::Instrument,
        40,
        400,
        1,
    )
    .unwrap();
    let a = &planned.analysis;
    assert!(a.identified[..6].iter().all(|p| p.is_instrument()));
    assert_eq!(a.identified.len(), 6 + 19);
    for p in [Param::Theta(0), Param::D(0), Param::A(0), Param::Alpha(0)] {
        assert!(a.unidentifiable.contains(&p), "{p}");
    }
    assert!(a.condition < 100.0, "{}", a.condition);
}

#[test]
fn measured_in_the_world_frame_fits_joint_1_and_no_instrument() {
    // An instrument registered to the world frame beforehand: joint 1's constants and the
    // [base] are the robot's to fit (the earlier behaviour). A tracker 2 m away then fits but
    // folds its placement into joint 1: the report calls that a modelling error.
    let nominal = robot("ur5");
    let truth = sim::perturb(&nominal, &sim::Errors::TYPICAL, 3).unwrap();
    let poses = plan::random_poses(&nominal, 50, 4).unwrap();
    let world = Options {
        measured_in: MeasuredIn::World,
        ..Options::with_noise(Some(NOISE))
    };
    let at_base = sim::measure(&truth, &poses, NOISE, 5);
    let result = calibrate(&nominal, &at_base, &[], &world).unwrap();
    assert!(result.fit.params.iter().all(|p| !p.is_instrument()));
    assert!(result.fit.params.contains(&Param::BaseXyz(1)));
    for p in [Param::Theta(0), Param::D(0), Param::A(0), Param::Alpha(0)] {
        assert!(result.fit.params.contains(&p), "{p}");
    }
    assert!(result.problems().is_empty(), "{:?}", result.problems());
    assert!(!result.report().contains("instrument frame in"));
    let far = sim::measure_from(&truth, &tracker(4), &poses, NOISE, 5);
    let result = calibrate(&nominal, &far, &[], &world).unwrap();
    assert!(result.large_moves().iter().any(|(p, _)| *p == Param::A(0)));
}

#[test]
fn a_result_worse_than_nominal_is_refused() {
    // An arm exactly as its file says: the fit can only add noise to it, so on held-out poses
    // it is no better than the nominal file, and the result is refused.
    let nominal = robot("ranger-mk1");
    let placement = tracker(8);
    let poses = plan::random_poses(&nominal, 50, 9).unwrap();
    let measured = sim::measure_from(&nominal, &placement, &poses, NOISE, 10);
    let check = plan::random_poses(&nominal, 100, 11).unwrap();
    let held_out = sim::measure_from(&nominal, &placement, &check, 0.0, 0);
    let options = Options::with_noise(Some(NOISE));
    let result = calibrate(&nominal, &measured, &held_out, &options).unwrap();
    let problems = result.problems();
    assert_eq!(problems.len(), 1, "{problems:?}");
    assert!(
        problems[0].contains("no better than the nominal"),
        "{problems:?}"
    );
}
