//! Forward kinematics and every closed-form IK solution for joint vectors read on standard
//! input, one JSON object per line: the armgate side of `tools/ik_crosscheck.py`, which
//! compares the solutions with an independent solver's.
//!
//! `cargo run --release -p armgate-core --example ik_solutions -- ROBOT.toml [--wide-limits]`
//!
//! Each input line is `fk q1 … qn` or `ik q1 … qn`. Both answer `{"pose": [16 numbers]}`, the
//! tool frame FK(q) as a row-major 4×4 matrix; `ik` adds `"solutions": [{"q": […], "branch":
//! b}, …], "micros": t`: `Chain::solve_all` of that pose and its time (µs), with the reference
//! at the middle of the joint ranges, or at `r1 … rn` if the line goes on with them (`ik q1 …
//! qn r1 … rn`: the reference also gives a joint that a singularity leaves free its value).
//! `--wide-limits` first sets every revolute joint's limits to ±2π (and so the reference to 0):
//! no solution is dropped by a limit and each branch comes back on its turn within ±π, what an
//! all-solutions solver without limits returns.
#![allow(missing_docs, clippy::unwrap_used)]

use std::f64::consts::TAU;
use std::io::{BufRead, Write};
use std::time::Instant;

use armgate_core::config::{JointType, load_file};
use armgate_core::kinematics::Chain;
use armgate_core::math::Frame;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(path) = args.iter().find(|a| !a.starts_with("--")) else {
        eprintln!("usage: ik_solutions ROBOT.toml [--wide-limits]");
        std::process::exit(2);
    };
    let mut robot = load_file(path).unwrap();
    if args.iter().any(|a| a == "--wide-limits") {
        robot = robot
            .edit(|config| {
                for joint in config.joints.iter_mut() {
                    if joint.kind == JointType::Revolute {
                        (joint.min, joint.max) = (-TAU, TAU);
                    }
                }
            })
            .unwrap();
    }
    let chain = Chain::new(&robot);
    let mid = chain.mid_range();
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    for line in std::io::stdin().lock().lines() {
        let line = line.unwrap();
        let mut words = line.split_whitespace();
        let Some(mode) = words.next() else { continue };
        let values: Vec<f64> = words.map(|w| w.parse().unwrap()).collect();
        let (q, given) = values.split_at(chain.dof());
        let pose = chain.forward(q).unwrap();
        write!(out, "{{\"pose\": {}", numbers(matrix(&pose).iter())).unwrap();
        if mode == "ik" {
            let reference: &[f64] = if given.is_empty() { &mid } else { given };
            let t0 = Instant::now();
            let solutions = chain.solve_all(&pose, reference).unwrap();
            let micros = t0.elapsed().as_secs_f64() * 1e6;
            let listed: Vec<String> = solutions
                .iter()
                .map(|s| {
                    let q = numbers(s.q.iter());
                    format!("{{\"q\": {q}, \"branch\": {}}}", s.branch.bits())
                })
                .collect();
            let listed = listed.join(", ");
            write!(out, ", \"solutions\": [{listed}], \"micros\": {micros:?}").unwrap();
        }
        writeln!(out, "}}").unwrap();
    }
}

/// The frame as a row-major 4×4 homogeneous matrix.
fn matrix(frame: &Frame) -> Vec<f64> {
    // nalgebra iterates column by column.
    frame.to_homogeneous().transpose().iter().copied().collect()
}

/// A JSON array of numbers, each with every digit (`{:?}` round-trips an f64).
fn numbers<'a>(values: impl Iterator<Item = &'a f64>) -> String {
    let listed: Vec<String> = values.map(|v| format!("{v:?}")).collect();
    format!("[{}]", listed.join(", "))
}
