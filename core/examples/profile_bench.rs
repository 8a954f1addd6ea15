//! Cost of planning one jerk-limited (double-S) profile on the host, and of a synchronised set
//! of six.
//!
//! `cargo run --release -p armgate-core --example profile_bench`
//!
//! The cases are the randomised test's (`core/tests/jerk_profile.rs`, [`RandomCase`], same
//! seed): limits over eight decades, either sign, half of them stretched to 1 + 1e-9 up to
//! 1001 times their minimum time. "Worst" is the slowest case, each call timed alone, the best of seven passes
//! (see `timings`).
#![allow(missing_docs, clippy::unwrap_used, clippy::indexing_slicing)]

use std::hint::black_box;
use std::time::Instant;

use armgate_core::motion::{DoubleS, RandomCase};
use armgate_core::rng::SplitMix64;

/// The randomised test's seed and case count.
const SEED: u64 = 0x6a65_726b;
const CASES: usize = 1_000_000;
/// Synchronised sets of six axes.
const SETS: usize = 100_000;
/// Timed passes over all cases for the worst case.
const PASSES: usize = 7;

/// Mean over `cases` (the best of [`PASSES`] passes, each timed as a whole), and single calls:
/// every call timed alone in each of [`PASSES`] passes over all cases in order (so branch
/// predictors see the real mix), the best of the passes per case (so a preemption does not
/// count as the profile's cost), less the cost of reading the clock twice.
fn timings<T: Copy>(cases: &[T], f: impl Fn(T) -> f64 + Copy) -> Timings {
    let mean = (0..PASSES)
        .map(|_| {
            let t0 = Instant::now();
            for case in cases {
                black_box(f(black_box(*case)));
            }
            t0.elapsed().as_nanos() as f64 / cases.len() as f64
        })
        .fold(f64::INFINITY, f64::min);
    let mut best = vec![f64::INFINITY; cases.len()];
    let mut clock = f64::INFINITY;
    for _ in 0..PASSES {
        for (case, best) in cases.iter().zip(&mut best) {
            let t0 = Instant::now();
            black_box(f(black_box(*case)));
            *best = best.min(t0.elapsed().as_nanos() as f64);
            let t0 = Instant::now();
            clock = clock.min(black_box(t0.elapsed().as_nanos() as f64));
        }
    }
    let (worst, index) = best
        .iter()
        .enumerate()
        .fold((0.0, 0), |a, (i, t)| if *t > a.0 { (*t, i) } else { a });
    best.sort_by(f64::total_cmp);
    let p999 = best[best.len() * 999 / 1000] - clock;
    Timings {
        mean,
        p999,
        worst: worst - clock,
        worst_index: index,
    }
}

/// Nanoseconds per call.
struct Timings {
    mean: f64,
    /// 99.9th percentile of the single-call times.
    p999: f64,
    worst: f64,
    worst_index: usize,
}

impl Timings {
    fn print(&self) {
        println!(
            "  mean {:.3} µs, 99.9th percentile {:.3} µs, worst {:.3} µs",
            self.mean / 1e3,
            self.p999 / 1e3,
            self.worst / 1e3
        );
    }
}

/// Plans six axes for minimum time, then stretches all to the slowest: what a synchronised
/// joint move with one profile per joint would do. Returns the common duration.
fn synchronised(set: [RandomCase; 6]) -> f64 {
    let plans = set.map(|c| DoubleS::new(c.distance, c.limits, 0.0).unwrap());
    let duration = plans.iter().map(DoubleS::duration).fold(0.0, f64::max);
    plans
        .map(|p| p.with_duration(duration).unwrap().duration())
        .into_iter()
        .fold(0.0, f64::max)
}

fn main() {
    let mut rng = SplitMix64::new(SEED);
    let cases: Vec<RandomCase> = (0..CASES).map(|_| RandomCase::draw(&mut rng)).collect();
    let plan = |case: RandomCase| case.plan().unwrap().duration();
    let one = timings(&cases, plan);
    println!("one profile, {CASES} random cases (seed {SEED:#x}):");
    one.print();
    println!("  slowest case: {:?}", cases[one.worst_index]);

    let sets: Vec<[RandomCase; 6]> = (0..SETS)
        .map(|_| core::array::from_fn(|_| RandomCase::draw(&mut rng)))
        .collect();
    println!("six axes synchronised (6 minimum-time plans + 6 stretched), {SETS} random sets:");
    timings(&sets, synchronised).print();
}
