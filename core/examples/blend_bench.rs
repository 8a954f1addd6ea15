//! Cost of planning one blend (`blend_into`: the next leg within the budgets, the blend start
//! by bisection, the fallback leg), on the host, for random corners.
//!
//! `cargo run --release -p armgate-core --example blend_bench`
//!
//! Each case: a generator runs a leg from a random point to a random via point, planned for a
//! blend there (`move_towards`); the time is that of one `blend_into` to a third random point
//! with a random tolerance (the prepared generator is cloned outside the timing). "blended" is
//! the share of cases in which the blend was worth it (the rest stop at the via point). Joint moves on ranger-mk1 (6 joints) and
//! ranger-mk2 (8), Cartesian moves on ranger-mk1's limits, each with trapezoidal and with
//! jerk-limited profiles.
#![allow(missing_docs, clippy::unwrap_used, clippy::indexing_slicing)]

use std::hint::black_box;
use std::time::Instant;

use armgate_core::config::{ValidRobot, load_file};
use armgate_core::kinematics::Joints;
use armgate_core::math::{Frame, Rotation3, Vector3};
use armgate_core::motion::{CartesianGenerator, JointGenerator, Refusal};
use armgate_core::rng::SplitMix64;

const CASES: usize = 20_000;

fn robot(name: &str) -> ValidRobot {
    load_file(format!(
        "{}/../robots/{name}.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}

fn report(what: &str, mut times: Vec<f64>, blended: usize) {
    times.sort_by(f64::total_cmp);
    let mean = times.iter().sum::<f64>() / times.len() as f64;
    let at = |q: f64| times[((times.len() - 1) as f64 * q) as usize];
    println!(
        "| {what:<34} | {CASES} | {:>9.1} | {mean:>7.2} | {:>9.2} | {:>6.2} | {:>6.2} |",
        blended as f64 / CASES as f64 * 100.0,
        at(0.5),
        at(0.99),
        times[times.len() - 1]
    );
}

/// Times `blend` on `CASES` prepared generators from `prepare` (with the next point and the
/// tolerance; cloned outside the timing) and prints the row.
fn measure<G: Clone, P>(
    name: &str,
    mut prepare: impl FnMut() -> (G, P, f64),
    blend: impl Fn(&mut G, P, f64) -> Result<bool, Refusal>,
) {
    let (mut times, mut blended) = (Vec::with_capacity(CASES), 0);
    for _ in 0..CASES {
        let (g, next, tolerance) = prepare();
        let mut g = black_box(g.clone());
        let t0 = Instant::now();
        let r = blend(&mut g, next, tolerance);
        times.push(t0.elapsed().as_secs_f64() * 1e6);
        blended += usize::from(black_box(r).unwrap());
    }
    report(name, times, blended);
}

fn random_joints(rng: &mut SplitMix64, config: &ValidRobot) -> Joints {
    let mut q = Joints::zeros(config.dof());
    for (v, j) in q.iter_mut().zip(&config.joints) {
        *v = rng.uniform(j.min, j.max);
    }
    q
}

fn joints(name: &str, robot_name: &str, jerk: bool, rng: &mut SplitMix64) {
    let config = robot(robot_name);
    let v = config.per_joint(|j| j.max_velocity);
    let a = config.per_joint(|j| j.max_acceleration);
    let j_max = jerk.then(|| config.per_joint(|j| j.max_jerk.unwrap_or(5.0)));
    let period = config.control_period;
    measure(
        name,
        || {
            let mut g =
                JointGenerator::new(random_joints(rng, &config), v, a).with_jerk_limits(j_max);
            let (goal, next) = (random_joints(rng, &config), random_joints(rng, &config));
            g.move_towards(goal, 0.0, Some(next)).unwrap();
            (g, next, rng.uniform(0.0, 0.2))
        },
        |g, next, tolerance| g.blend_into(next, 0.0, tolerance, None, period),
    );
}

fn random_pose(rng: &mut SplitMix64) -> Frame {
    let p = Vector3::new(
        rng.uniform(-0.5, 0.5),
        rng.uniform(-0.5, 0.5),
        rng.uniform(0.2, 1.0),
    );
    let r = Rotation3::from_euler_angles(
        rng.uniform(-1.0, 1.0),
        rng.uniform(-1.0, 1.0),
        rng.uniform(-1.0, 1.0),
    );
    Frame::from_parts(p.into(), r)
}

fn cartesian(name: &str, jerk: bool, rng: &mut SplitMix64) {
    let config = robot("ranger-mk1");
    let c = &config.cartesian;
    let j_max = jerk.then_some([0.02, 0.02, 0.02, 0.1, 0.1, 0.1]);
    let period = config.control_period;
    measure(
        name,
        || {
            let mut g =
                CartesianGenerator::new(random_pose(rng), c.max_velocity, c.max_acceleration)
                    .with_jerk_limits(j_max);
            let (goal, next) = (random_pose(rng), random_pose(rng));
            g.move_towards(goal, 0.0, Some(next)).unwrap();
            (g, next, rng.uniform(0.0, 0.05))
        },
        |g, next, tolerance| g.blend_into(next, 0.0, tolerance, None, period),
    );
}

fn main() {
    let mut rng = SplitMix64::new(13);
    println!(
        "| blend_into                         | cases | blended % | mean µs | median µs | p99 µs | max µs |"
    );
    println!(
        "|------------------------------------|-------|-----------|---------|-----------|--------|--------|"
    );
    joints(
        "joints, ranger-mk1, trapezoid",
        "ranger-mk1",
        false,
        &mut rng,
    );
    joints(
        "joints, ranger-mk1, jerk-limited",
        "ranger-mk1",
        true,
        &mut rng,
    );
    joints(
        "joints, ranger-mk2 (8), trapezoid",
        "ranger-mk2",
        false,
        &mut rng,
    );
    cartesian("Cartesian, trapezoid", false, &mut rng);
    cartesian("Cartesian, jerk-limited", true, &mut rng);
}
