//! Planning one jerk-limited profile, `DoubleS::new(distance, limits, min_duration)`, on the
//! first [`CASES`] of the randomised test's cases (`core/tests/jerk_profile.rs`: same
//! [`RandomCase`] distribution, same seed, so the same inputs as the host benchmark
//! `core/examples/profile_bench.rs`), split into minimum-time and stretched requests; and six
//! axes synchronised (six minimum-time plans, then all six stretched to the slowest).

use core::hint::black_box;

use armgate_core::motion::{DoubleS, ProfileError, RandomCase};
use armgate_core::rng::SplitMix64;
use cortex_m_semihosting::hprintln;

use crate::counter::{Counter, Timing, measure};

/// The randomised test's seed.
const SEED: u64 = 0x6a65_726b;
/// Cases measured: all of the randomised test's CI-sized run.
const CASES: u32 = 1_000_000;
/// Synchronised sets of six axes, drawn after the cases.
const SETS: u32 = 10_000;

/// Measures and prints the table; false if a case could not be planned.
pub fn run(counter: &Counter) -> bool {
    let mut rng = SplitMix64::new(SEED);
    let (mut fastest, mut stretched, mut sets) =
        (Timing::default(), Timing::default(), Timing::default());
    let mut errors = 0u32;
    for _ in 0..CASES {
        let case = RandomCase::draw(&mut rng);
        let (ticks, planned) = measure(|| black_box(case).plan());
        if case.min_duration > 0.0 {
            stretched.add(ticks);
        } else {
            fastest.add(ticks);
        }
        errors += u32::from(planned.is_err());
    }
    for _ in 0..SETS {
        let set: [RandomCase; 6] = core::array::from_fn(|_| RandomCase::draw(&mut rng));
        let (ticks, planned) = measure(|| synchronised(black_box(&set)));
        sets.add(ticks);
        errors += u32::from(planned.is_err());
    }
    counter.print_calibration();
    hprintln!(
        "jerk-limited profiles: {} random cases (seed {:#x}), {} sets of six; instructions per call, mean (max)",
        CASES,
        SEED,
        SETS
    );
    hprintln!("| request                                 | calls   | instructions/call     |");
    hprintln!("|-----------------------------------------|---------|-----------------------|");
    let row = |request: &str, timing: &Timing| {
        let (mean, max) = timing.instructions(counter);
        hprintln!(
            "| {:<39} | {:>7} | {:>9.0} ({:>9.0}) |",
            request,
            timing.calls,
            mean,
            max
        );
    };
    row("one profile, minimum time", &fastest);
    row("one profile, stretched to a duration", &stretched);
    row("six axes synchronised (6 + 6 stretched)", &sets);
    if errors > 0 {
        hprintln!("{} requests refused", errors);
    }
    errors == 0
}

/// Six minimum-time plans, then all six stretched to the slowest; the common duration.
fn synchronised(set: &[RandomCase; 6]) -> Result<f64, ProfileError> {
    let mut plans = [None; 6];
    let mut duration = 0.0f64;
    for (plan, case) in plans.iter_mut().zip(set) {
        let p = DoubleS::new(case.distance, case.limits, 0.0)?;
        duration = duration.max(p.duration());
        *plan = Some(p);
    }
    let mut common = 0.0f64;
    for p in plans.into_iter().flatten() {
        common = common.max(p.with_duration(duration)?.duration());
    }
    Ok(common)
}
