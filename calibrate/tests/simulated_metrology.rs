//! Issue 15's acceptance: calibrate simulated arms with known errors from 50 planned poses
//! measured with 0.05 mm noise, and check the result on 100 held-out poses.
#![allow(clippy::unwrap_used, clippy::panic)] // helpers of tests: a panic is a failed test

use armgate_calibrate::calibration::{Options, Validation, calibrate};
use armgate_calibrate::fit::{self, Residuals};
use armgate_calibrate::model::{self, FitSet, Geometry, MeasuredIn, Param};
use armgate_calibrate::{identify, plan, sim};
use armgate_core::config::{ValidRobot, load_file};
use armgate_core::kinematics::Chain;

fn robot(name: &str) -> ValidRobot {
    load_file(format!(
        "{}/../robots/{name}.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}

const NOISE: f64 = 0.05e-3;

/// What a scenario found beyond its accuracy checks.
struct Outcome {
    report: String,
    /// Held-out errors of the calibrated model.
    after: Residuals,
    unidentifiable: Vec<Param>,
    /// The identified parameter farthest from the truth, and that distance in σ.
    worst: (Param, f64),
}

/// Runs the whole scenario, asserting the accuracy figures.
fn scenario(name: &str, seed: u64) -> Outcome {
    let nominal = robot(name);
    let truth = sim::perturb(&nominal, &sim::Errors::TYPICAL, seed).unwrap();
    let plan = plan::plan(
        &nominal,
        FitSet::All,
        MeasuredIn::Instrument,
        50,
        1000,
        seed,
    )
    .unwrap();
    let measured = sim::measure(&truth, &plan.poses, NOISE, seed + 1);
    let check_poses = plan::random_poses(&nominal, 100, seed + 2).unwrap();
    // Held-out poses measured without noise: the errors are the model's, not the instrument's.
    let held_out = sim::measure(&truth, &check_poses, 0.0, 0);
    let result = calibrate(
        &nominal,
        &measured,
        &held_out,
        &Options::with_noise(Some(NOISE)),
    )
    .unwrap();
    let report = result.report();

    let Validation::HeldOut { before, after } = result.validation else {
        panic!("held-out poses were given")
    };
    assert!(
        before.mean > 1e-3,
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
    // that absorb the errors of the fixed ones (e.g. base.z goes into J1.d). Away from nominal
    // the redundancy holds only approximately: the fixed J6.theta moves a tool point that the
    // errors put up to 1.4 mm off axis 6 (0.5° · 1.4 mm ≈ 12 µm), and the d of axes tilted by
    // 0.05° (≈ 1 µm). So "the truth" is the noise-free fit at the same poses — what the estimate
    // is the noisy version of — and it must reproduce the arm to well below the noise.
    let exact = sim::measure(&truth, &plan.poses, 0.0, 0);
    let equivalent = calibrate(&nominal, &exact, &[], &Options::with_noise(None))
        .unwrap()
        .fit;
    let residual = Residuals::of(&equivalent.geometry, &exact);
    assert!(
        residual.max < 0.025e-3,
        "the reduced model misses the truth by {} m",
        residual.max
    );
    let mut worst = (Param::Theta(0), 0.0);
    // (The instrument's parameters correct registrations that differ; tests/tracker.rs checks
    // its placement.)
    let params = result.fit.params.iter().zip(&result.fit.std_dev);
    for (p, sd) in params.filter(|(p, _)| !p.is_instrument()) {
        let sigmas = (result.fit.geometry.get(*p) - equivalent.geometry.get(*p)).abs() / sd;
        if sigmas > worst.1 {
            worst = (*p, sigmas);
        }
    }
    for p in &result.analysis.unidentifiable {
        assert!(report.contains(&p.to_string()), "{p} not in the report");
    }
    Outcome {
        report,
        after,
        unidentifiable: result.analysis.unidentifiable.clone(),
        worst,
    }
}

// Both arms: the instrument's frame takes joint 1's theta, a, d and alpha (and the [base]
// frame, not a candidate); the tool lies on axis 6, so its offset does not show and a_5,
// alpha_5 and the tool's z duplicate other lengths; parallel axes share one d.

/// Runs `scenario(name, seed)`: every identified parameter within 4.5σ of the truth (with about
/// 25 parameters one beyond 3σ is expected by chance in 6.5 % of seeds, see [`many_seeds`]; ur5's
/// seed 5 has J4.theta at 3.03σ since the plan keeps the arm clear), and exactly
/// `unidentifiable` left nominal.
fn calibrates(name: &str, seed: u64, unidentifiable: &str) {
    let outcome = scenario(name, seed);
    println!("{}", outcome.report);
    assert!(
        outcome.worst.1 < 4.5,
        "{} off by {:.2}σ",
        outcome.worst.0,
        outcome.worst.1
    );
    assert_eq!(model::list(&outcome.unidentifiable), unidentifiable);
}

#[test]
fn ranger_mk1_calibrates_to_a_tenth_of_a_millimetre() {
    calibrates(
        "ranger-mk1",
        15,
        "J1.theta, J6.theta, J1.a, J1.d, J3.d, J6.a, tool.z, J1.alpha, J6.alpha",
    );
}

#[test]
fn ur5_calibrates_to_a_tenth_of_a_millimetre() {
    // Axes 2, 3 and 4 are parallel: only one of d2, d3, d4 can be identified.
    calibrates(
        "ur5",
        5,
        "J1.theta, J6.theta, J1.a, J1.d, J3.d, J4.d, J6.a, tool.z, J1.alpha, J6.alpha",
    );
}

/// 50 seeds per arm (about a minute: `cargo test -p armgate-calibrate --test
/// simulated_metrology -- --ignored --nocapture`). Accuracy must hold for every seed. With about
/// 25 parameters, a seed whose worst parameter lies beyond 3σ is expected by chance (6.5 % of
/// seeds for independent Gaussian errors); beyond 4.5σ it is not (0.02 %).
#[test]
#[ignore]
fn many_seeds() {
    let mut beyond_3 = 0;
    let mut worst: f64 = 0.0;
    let (mut mean, mut max): (f64, f64) = (0.0, 0.0);
    for seed in 100..150 {
        for name in ["ranger-mk1", "ur5"] {
            let outcome = scenario(name, seed);
            if outcome.worst.1 > 3.0 {
                beyond_3 += 1;
                eprintln!(
                    "{name} seed {seed}: {} off by {:.2}σ",
                    outcome.worst.0, outcome.worst.1
                );
            }
            worst = worst.max(outcome.worst.1);
            mean = mean.max(outcome.after.mean);
            max = max.max(outcome.after.max);
        }
    }
    eprintln!(
        "100 scenarios: held-out error at most {:.3} mm mean, {:.3} mm max; {beyond_3} with a \
         parameter beyond 3σ, the worst {worst:.2}σ",
        mean * 1e3,
        max * 1e3
    );
    assert!(worst < 4.5);
}

#[test]
fn the_model_is_cores_forward_kinematics() {
    for name in ["ranger-mk1", "ur5", "hybrid", "ranger-mk2"] {
        let truth = sim::perturb(&robot(name), &sim::Errors::TYPICAL, 3).unwrap();
        let chain = Chain::new(&truth);
        let geometry = Geometry::new(&truth);
        for q in plan::random_poses(&robot(name), 20, 4).unwrap() {
            let core = chain.forward(&q).unwrap().translation.vector;
            let diff = (core - geometry.position(&q)).norm();
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
    let truth = nominal.clone().edit(|c| c.joints[2].beta = 0.001).unwrap();
    let poses = plan::plan(&nominal, FitSet::All, MeasuredIn::Instrument, 50, 600, 1)
        .unwrap()
        .poses;
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
            .candidates(FitSet::All, MeasuredIn::Instrument)
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
