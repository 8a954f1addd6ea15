//! Issue 15's acceptance: calibrate simulated arms with known errors from 50 planned poses
//! measured with 0.05 mm noise, and check the result on 100 held-out poses.
#![allow(clippy::unwrap_used, clippy::panic)] // helpers of tests: a panic is a failed test

use armgate_calibrate::calibration::{Validation, calibrate};
use armgate_calibrate::fit::{self, Residuals};
use armgate_calibrate::model::{self, FitSet, Geometry, Param};
use armgate_calibrate::{identify, plan, sim};
use armgate_core::config::{RobotConfig, load_file};
use armgate_core::kinematics::Chain;

fn robot(name: &str) -> RobotConfig {
    load_file(format!(
        "{}/../robots/{name}.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}

const NOISE: f64 = 0.05e-3;

/// Runs the whole scenario and returns the unidentifiable parameters.
fn scenario(name: &str, seed: u64) -> Vec<Param> {
    let nominal = robot(name);
    let truth = sim::perturb(&nominal, &sim::Errors::TYPICAL, seed);
    let plan = plan::plan(&nominal, FitSet::All, 50, 1000, seed).unwrap();
    let measured = sim::measure(&truth, &plan.poses, NOISE, seed + 1);
    let check_poses = plan::random_poses(&nominal, 100, seed + 2).unwrap();
    // Held-out poses measured without noise: the errors are the model's, not the instrument's.
    let held_out = sim::measure(&truth, &check_poses, 0.0, 0);
    let result = calibrate(&nominal, &measured, &held_out, FitSet::All).unwrap();
    println!("{name}:\n{}", result.report());

    let Validation::HeldOut { before, after } = result.validation else {
        panic!("held-out poses were given")
    };
    assert!(
        before.mean > 2e-3,
        "nominal error only {:.3} mm",
        before.mean * 1e3
    );
    assert!(after.mean <= 0.10e-3, "mean {:.4} mm", after.mean * 1e3);
    assert!(after.max <= 0.30e-3, "max {:.4} mm", after.max * 1e3);
    assert!(
        result.analysis.condition < 100.0,
        "condition {}",
        result.analysis.condition
    );

    // The truth in the identified parametrisation: the unidentifiable parameters are redundant
    // at the nominal geometry, so the identified ones alone reproduce the true arm — with values
    // that absorb the errors of the fixed ones. Away from nominal the redundancy holds to second
    // order only (e.g. d of two axes tilted by 0.05°: 1 mm · 0.05° ≈ 1 µm), so the reduced model
    // matches the truth to some µm, far below the noise. Each estimate must lie within 3σ of
    // those values, which is what the fit converges to with endless noise-free data.
    let exact = sim::measure(
        &truth,
        &plan::random_poses(&nominal, 200, seed + 3).unwrap(),
        0.0,
        0,
    );
    let start = Geometry::new(&nominal);
    let equivalent = fit::fit(&start, &result.fit.params, &exact).unwrap();
    let residual = Residuals::of(&equivalent.geometry, &exact);
    assert!(
        residual.max < 0.01e-3,
        "the reduced model misses the truth by {} m",
        residual.max
    );
    for (p, sd) in result.fit.params.iter().zip(&result.fit.std_dev) {
        let estimate = result.fit.geometry.get(*p);
        let true_value = equivalent.geometry.get(*p);
        assert!(
            (estimate - true_value).abs() <= 3.0 * sd,
            "{name} {p}: estimate {estimate} truth {true_value} σ {sd}"
        );
    }
    let report = result.report();
    for p in &result.analysis.unidentifiable {
        assert!(report.contains(&p.to_string()), "{p} not in the report");
    }
    result.analysis.unidentifiable.clone()
}

// Both arms: the base pose's x, z, roll and yaw duplicate joint 1's a, d, alpha and theta; the
// tool lies on axis 6, so its offset does not show and a_5, alpha_5 and the tool's z duplicate
// other lengths; parallel axes share one d.

#[test]
fn ranger_mk1_calibrates_to_a_tenth_of_a_millimetre() {
    let unidentifiable = scenario("ranger-mk1", 15);
    assert_eq!(
        model::list(&unidentifiable),
        "J6.theta, J3.d, J6.a, tool.z, J6.alpha, base.x, base.z, base.roll, base.yaw"
    );
}

#[test]
fn ur5_calibrates_to_a_tenth_of_a_millimetre() {
    // Axes 2, 3 and 4 are parallel: only one of d2, d3, d4 can be identified.
    let unidentifiable = scenario("ur5", 5);
    assert_eq!(
        model::list(&unidentifiable),
        "J6.theta, J3.d, J4.d, J6.a, tool.z, J6.alpha, base.x, base.z, base.roll, base.yaw"
    );
}

#[test]
fn the_model_is_cores_forward_kinematics() {
    for name in ["ranger-mk1", "ur5", "hybrid", "ranger-mk2"] {
        let truth = sim::perturb(&robot(name), &sim::Errors::TYPICAL, 3);
        let chain = Chain::new(&truth);
        let geometry = Geometry::new(&truth);
        for q in plan::random_poses(&robot(name), 20, 4).unwrap() {
            let core = chain.forward(&q).unwrap().pos;
            let ours = geometry.position(&q);
            let diff =
                ((core.x - ours.x).powi(2) + (core.y - ours.y).powi(2) + (core.z - ours.z).powi(2))
                    .sqrt();
            assert!(diff < 1e-12, "{name}: {diff}");
        }
    }
}

#[test]
fn hayati_beta_absorbs_a_tilt_between_parallel_axes() {
    // ur5's axes 2 and 3 are parallel; tilt axis 3 by 0.06° about y. Plain DH can express that
    // only by moving the common normal (and d) metres away — not a small correction — so
    // without β the fit is left with the tilt; with β it is exact.
    let nominal = robot("ur5");
    let mut truth = nominal.clone();
    truth.joints[2].beta = 0.001;
    let poses = plan::plan(&nominal, FitSet::All, 50, 600, 1).unwrap().poses;
    let measured = sim::measure(&truth, &poses, 0.0, 0);
    let check = sim::measure(
        &truth,
        &plan::random_poses(&nominal, 100, 2).unwrap(),
        0.0,
        0,
    );
    let start = Geometry::new(&nominal);
    let max_error = |with_beta: bool| {
        let candidates: Vec<Param> = start
            .candidates(FitSet::All)
            .into_iter()
            .filter(|p| with_beta || !matches!(p, Param::Beta(_)))
            .collect();
        let params = identify::analyse(&start, &candidates, &poses).identified;
        let fitted = fit::fit(&start, &params, &measured).unwrap();
        Residuals::of(&fitted.geometry, &check).max
    };
    let (with, without) = (max_error(true), max_error(false));
    println!("max error with β {:.2e} m, without {:.2e} m", with, without);
    assert!(with < 1e-6, "{with}");
    assert!(without > 0.1e-3, "{without}");
}
