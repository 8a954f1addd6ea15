//! What the up-front check of a Cartesian move's straight line costs, and what it says.
//!
//! `cargo run --release -p armgate-core --example reach_bench [-- MOVES]`
//!
//! For every shipped robot: random Cartesian goals 2–60 cm (and up to 1 rad) from a random
//! configuration (fixed seed), each checked by `Controller::move_cartesian` in Cartesian mode
//! (the check plus planning). The time of a check is the fastest of three runs (the machine is
//! shared); printed: mean, 99th percentile and worst, with and without the check, and how many
//! moves it refused. Then, on a subset, every move is also run without the check on an ideal
//! arm: "agree" counts moves that the check accepted and that completed, or that it refused
//! and that did not reach the goal. Last, the README's example move on ranger-mk1.
#![allow(missing_docs, clippy::indexing_slicing, clippy::unwrap_used)]

use std::time::Instant;

use armgate_core::config::{ValidRobot, load_file};
use armgate_core::kinematics::{Chain, Joints};
use armgate_core::math::{self, Frame, Rotation3, Vector3};
use armgate_core::motion::{Controller, Mode, SOLVES_PER_LINE, StopCause, check_iterations};
use armgate_core::rng::SplitMix64;

const SEED: u64 = 0x5EED_0016;

fn robot(name: &str) -> ValidRobot {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    load_file(root.join("robots").join(format!("{name}.toml"))).unwrap()
}

/// A controller in Cartesian mode holding at `q`.
fn holding_at(config: &ValidRobot, q: &Joints) -> Controller {
    let mut ctrl = Controller::new(config);
    ctrl.step(0.0, q).unwrap();
    ctrl.set_mode(Mode::Cartesian).unwrap();
    ctrl
}

fn row(robot: &str, check: bool, micros: &mut [f64], refused: usize) {
    micros.sort_by(f64::total_cmp);
    let n = micros.len();
    let mean = micros.iter().sum::<f64>() / n as f64;
    let p99 = micros[((n as f64 * 0.99) as usize).min(n - 1)];
    println!(
        "| {robot:<18} | {:<5} | {n:>5} | {mean:>9.1} | {p99:>9.1} | {:>9.1} | {:>7.1} |",
        if check { "on" } else { "off" },
        micros[n - 1],
        100.0 * refused as f64 / n as f64
    );
}

fn bench(name: &str, moves: usize) {
    let base = robot(name);
    let chain = Chain::new(&base);
    for check in [true, false] {
        let config = base.clone().edit(|c| c.ik.check_lines = check).unwrap();
        let mut rng = SplitMix64::new(SEED);
        let (mut micros, mut refused) = (Vec::new(), 0);
        let mut agreement = Vec::new();
        while micros.len() < moves {
            let mut q = chain.mid_range();
            for (v, (lo, hi)) in q.iter_mut().zip(chain.min().iter().zip(chain.max())) {
                *v = lo + (hi - lo) * rng.next_f64();
            }
            let start = chain.forward(&q).unwrap();
            let mut ctrl = holding_at(&config, &q);
            if ctrl.move_cartesian(start, 0.0).is_err() {
                continue; // the start itself is outside the workspace
            }
            ctrl.stop(StopCause::Stop);
            let dir = Vector3::new(
                rng.next_f64() - 0.5,
                rng.next_f64() - 0.5,
                rng.next_f64() - 0.5,
            );
            let length = 0.02 + 0.58 * rng.next_f64();
            let turn = Vector3::new(
                rng.next_f64() - 0.5,
                rng.next_f64() - 0.5,
                rng.next_f64() - 0.5,
            );
            let goal = Frame::from_parts(
                (start.translation.vector + dir * (length / dir.norm())).into(),
                Rotation3::new(turn * rng.next_f64()) * start.rotation,
            );
            let mut fastest = f64::INFINITY;
            let mut result = Ok(0.0);
            for _ in 0..3 {
                let mut fresh = ctrl.clone();
                let t = Instant::now();
                result = fresh.move_cartesian(goal, 0.0);
                fastest = fastest.min(t.elapsed().as_secs_f64() * 1e6);
            }
            micros.push(fastest);
            refused += usize::from(result.is_err());
            if check && agreement.len() < AGREEMENT_MOVES {
                agreement.push((result.is_ok(), completes(&base, &q, goal)));
            }
        }
        row(name, check, &mut micros, refused);
        if check {
            let agree = agreement.iter().filter(|(a, b)| a == b).count();
            let false_refusals = agreement.iter().filter(|(a, b)| !a && *b).count();
            println!(
                "|   agreement with the run, {} moves: {agree} agree, {false_refusals} refused but completed, {} accepted but stopped |",
                agreement.len(),
                agreement.len() - agree - false_refusals
            );
        }
    }
}

/// Moves run without the check, for the agreement figure.
const AGREEMENT_MOVES: usize = 100;

/// Whether the move from `q` to `goal` completes without the check (ideal arm): it reaches
/// the goal within 1 mm and 1 mrad.
fn completes(config: &ValidRobot, q: &Joints, goal: Frame) -> bool {
    let config = config.clone().edit(|c| c.ik.check_lines = false).unwrap();
    let chain = Chain::new(&config);
    let mut ctrl = holding_at(&config, q);
    let Ok(duration) = ctrl.move_cartesian(goal, 0.0) else {
        return false;
    };
    let mut q = *q;
    let mut now = 0.0;
    // Slowed-down motions may take longer than planned; a stall aborts within 0.5 s.
    for _ in 0..(4.0 * duration / config.control_period) as usize + 100 {
        now += config.control_period;
        if let Some(c) = ctrl.step(now, &q).unwrap().command {
            q = c;
        }
        if !ctrl.is_moving() {
            break;
        }
    }
    let reached = chain.forward(&q).unwrap();
    let error = math::diff(&reached, &goal);
    error.fixed_rows::<3>(0).norm() < 1e-3 && error.fixed_rows::<3>(3).norm() < 1e-3
}

/// The README's `armgate move 0.5 0.2 0.1 0 0 0 --time 5` from ranger-mk1's home.
fn readme_move() {
    let config = robot("ranger-mk1");
    let home = config.home();
    let goal = Frame::from_parts(
        Vector3::new(0.5, 0.2, 0.1).into(),
        Rotation3::from_euler_angles(0.0, 0.0, 0.0),
    );
    let mut ctrl = holding_at(&config, &home);
    let t = Instant::now();
    let verdict = ctrl.move_cartesian(goal, 5.0);
    let micros = t.elapsed().as_secs_f64() * 1e6;
    println!("README move on ranger-mk1 from home: {verdict:?} ({micros:.0} µs)");
    if let Err(refusal) = verdict {
        println!("  refused: {refusal}");
    }

    // Without the check: how far the move gets and where it stops.
    let config = config.clone().edit(|c| c.ik.check_lines = false).unwrap();
    let mut ctrl = holding_at(&config, &home);
    let duration = ctrl.move_cartesian(goal, 5.0).unwrap();
    let mut q = home;
    let mut now = 0.0;
    for _ in 0..(duration / config.control_period) as usize + 100 {
        now += config.control_period;
        let out = ctrl.step(now, &q).unwrap();
        if let Some(c) = out.command {
            q = c;
        }
        if !ctrl.is_moving() {
            break;
        }
    }
    let chain = Chain::new(&config);
    let reached = chain.forward(&q).unwrap().translation.vector;
    let start = chain.forward(&home).unwrap().translation.vector;
    let fraction = (reached - start).norm() / (goal.translation.vector - start).norm();
    println!(
        "  without the check: planned {duration:.1} s, stopped after {now:.2} s at {:.0}% of the line, joints {:.3?}",
        100.0 * fraction,
        &q[..]
    );
    let (lo, hi) = (chain.min(), chain.max());
    for (j, v) in q.iter().enumerate() {
        if (v - lo[j]).abs() < 1e-6 || (v - hi[j]).abs() < 1e-6 {
            println!("  joint {} is at its limit [{}, {}]", j + 1, lo[j], hi[j]);
        }
    }
}

fn main() {
    let moves = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(2000);
    println!(
        "at most {SOLVES_PER_LINE} tracking solves per line; IK iterations per request: {} at 19.44 ms, {} at 5.04 ms",
        check_iterations(0.01944),
        check_iterations(0.00504)
    );
    println!(
        "| robot              | check | moves | mean (µs) | p99 (µs)  | max (µs)  | refused % |"
    );
    println!(
        "|--------------------|-------|-------|-----------|-----------|-----------|---------|"
    );
    for name in ["ranger-mk1", "ranger-mk2", "ur5", "puma560", "iiwa14"] {
        bench(name, moves);
    }
    readme_move();
}
