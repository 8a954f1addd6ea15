//! IK benchmark on every shipped robot, following TRAC-IK's protocol.
//!
//! `cargo run --release -p armgate-core --example ik_bench [-- SAMPLES]`
//!
//! * global: random reachable configurations (fixed seed) → FK → target; the solver is seeded
//!   at the middle of the joint ranges.
//! * tracking: seeded at the target configuration + uniform ±0.1 rad (m for prismatic joints).
//!
//! Success: position error < 1e-5 m, orientation error < 1e-5 rad and all joints within limits.
//!
//! * all: every solution in closed form (`Chain::solve_all`, robots of a closed-form family),
//!   reference at the middle of the joint ranges; success = the configuration the target came
//!   from is among the solutions (up to whole turns); `sols` is the mean number of solutions.
//!   A redundant arm (`SphericalShoulder`) is given the configuration's own redundancy
//!   parameters (θ3, and θ5 on eight joints) in the reference: its solutions for them.
//!
//! A further table times global solves of unreachable targets (10 m from the base, random
//! orientation): every one spends the whole `ik.global_iterations` budget, so its maximum is
//! the worst case of a global solve.
#![allow(missing_docs, clippy::indexing_slicing, clippy::unwrap_used)]

use std::time::Instant;

use armgate_core::config::IkConfig;
use armgate_core::config::load_file;
use std::f64::consts::TAU;

use armgate_core::kinematics::{Chain, Family, IkResult};
use armgate_core::math::{self, Frame, Rotation3, Vector3};
use armgate_core::rng::SplitMix64;

const SEED: u64 = 0x1C0FFEE;

struct Stats {
    successes: usize,
    micros: Vec<f64>,
    iterations: u64,
}

impl Stats {
    fn row(&mut self, robot: &str, mode: &str) {
        self.micros.sort_by(f64::total_cmp);
        let n = self.micros.len();
        let mean = self.micros.iter().sum::<f64>() / n as f64;
        let pct = |p: f64| self.micros[((n as f64 * p) as usize).min(n - 1)];
        println!(
            "| {robot:<18} | {mode:<8} | {:>8.3} | {:>9.2} | {:>9.2} | {:>9.2} | {:>6.1} |",
            100.0 * self.successes as f64 / n as f64,
            mean,
            pct(0.5),
            pct(0.99),
            self.iterations as f64 / n as f64
        );
    }
}

fn success(chain: &Chain, target: &Frame, result: &IkResult) -> bool {
    let s = result.solution();
    let reached = chain.forward(&s.q).unwrap();
    let d = math::diff(&reached, target);
    d.fixed_rows::<3>(0).norm() < 1e-5
        && d.fixed_rows::<3>(3).norm() < 1e-5
        && chain.within_limits(&s.q)
}

fn main() {
    let samples: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(10_000);
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../robots");
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    let mut unreachable = Vec::new();
    let mut closed = Vec::new();
    println!("{samples} samples per robot and mode, seed {SEED:#x}");
    println!(
        "| robot              | mode     | success% | mean µs   | median µs | p99 µs    | iters  |"
    );
    println!(
        "|--------------------|----------|----------|-----------|-----------|-----------|--------|"
    );
    for path in files {
        let config = load_file(&path).unwrap();
        let chain = Chain::new(&config);
        let ik = config.ik;
        let mut rng = SplitMix64::new(SEED);
        let mut global = Stats {
            successes: 0,
            micros: Vec::new(),
            iterations: 0,
        };
        let mut tracking = Stats {
            successes: 0,
            micros: Vec::new(),
            iterations: 0,
        };
        let mid = chain.mid_range();
        for k in 0..samples {
            let q = chain.random_joints(&mut rng);
            let target = chain.forward(&q).unwrap();

            let t0 = Instant::now();
            let r = chain.solve_global(&target, &mid, &ik, k as u64).unwrap();
            global.micros.push(t0.elapsed().as_secs_f64() * 1e6);
            global.iterations += u64::from(r.solution().iterations);
            global.successes += usize::from(success(&chain, &target, &r));

            let seed: Vec<f64> = q.iter().map(|v| v + rng.uniform(-0.1, 0.1)).collect();
            let t0 = Instant::now();
            let r = chain.solve_tracking(&target, &seed, &ik).unwrap();
            tracking.micros.push(t0.elapsed().as_secs_f64() * 1e6);
            tracking.iterations += u64::from(r.solution().iterations);
            tracking.successes += usize::from(success(&chain, &target, &r));
        }
        if chain.family().family != Family::Numeric {
            closed.push((config.name.to_string(), all_solutions(&chain, samples)));
        }
        let name = config.name.as_str();
        global.row(name, "global");
        tracking.row(name, "tracking");
        unreachable.push((
            config.name.to_string(),
            ik.global_iterations,
            worst_case(&chain, &ik),
        ));
    }
    println!();
    println!("every solution in closed form, {samples} samples per robot, seed {SEED:#x}");
    println!(
        "| robot              | family            | success% | mean µs   | median µs | p99 µs    | sols   |"
    );
    println!(
        "|--------------------|-------------------|----------|-----------|-----------|-----------|--------|"
    );
    for (name, (family, mut stats)) in closed {
        stats.row(&name, &format!("{:<17}", format!("{family:?}")));
    }
    println!();
    println!("global IK on unreachable targets, {UNREACHABLE_SAMPLES} samples per robot");
    println!("| robot              | budget | iterations | mean µs   | max µs    |");
    println!("|--------------------|--------|------------|-----------|-----------|");
    for (name, budget, (iterations, mean, max)) in unreachable {
        println!("| {name:<18} | {budget:>6} | {iterations:>10} | {mean:>9.2} | {max:>9.2} |");
    }
}

/// All-solutions solves of random reachable targets; `iterations` counts the solutions.
fn all_solutions(chain: &Chain, samples: usize) -> (Family, Stats) {
    let mut rng = SplitMix64::new(SEED);
    let mid = chain.mid_range();
    let mut stats = Stats {
        successes: 0,
        micros: Vec::new(),
        iterations: 0,
    };
    for _ in 0..samples {
        let q = chain.random_joints(&mut rng);
        let target = chain.forward(&q).unwrap();
        let mut reference = mid;
        if chain.family().family == Family::SphericalShoulder {
            let parameters: &[usize] = if chain.dof() == 8 { &[2, 4] } else { &[2] };
            for &p in parameters {
                reference[p] = q[p];
            }
        }
        let t0 = Instant::now();
        let solutions = chain.solve_all(&target, &reference).unwrap();
        stats.micros.push(t0.elapsed().as_secs_f64() * 1e6);
        stats.iterations += solutions.len() as u64;
        let found = solutions.iter().any(|s| {
            s.q.iter().zip(q.iter()).all(|(a, b)| {
                let d = a - b;
                (d - TAU * (d / TAU).round()).abs() < 1e-6
            })
        });
        stats.successes += usize::from(found);
    }
    (chain.family().family, stats)
}

const UNREACHABLE_SAMPLES: usize = 200;

/// Global solves of unreachable targets: (largest iteration count, mean µs, max µs).
fn worst_case(chain: &Chain, ik: &IkConfig) -> (u32, f64, f64) {
    let mut rng = SplitMix64::new(SEED);
    let mid = chain.mid_range();
    let (mut iterations, mut total, mut max) = (0, 0.0, 0.0f64);
    for k in 0..UNREACHABLE_SAMPLES {
        let direction = Vector3::new(
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
        )
        .normalize();
        let turn = Vector3::new(
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
        );
        let target = Frame::from_parts((direction * 10.0).into(), Rotation3::new(turn));
        let t0 = Instant::now();
        let r = chain.solve_global(&target, &mid, ik, k as u64).unwrap();
        let micros = t0.elapsed().as_secs_f64() * 1e6;
        assert!(!r.is_converged());
        iterations = iterations.max(r.solution().iterations);
        total += micros;
        max = max.max(micros);
    }
    (iterations, total / UNREACHABLE_SAMPLES as f64, max)
}
