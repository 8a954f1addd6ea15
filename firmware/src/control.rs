//! The periodic control tick.
//!
//! For now the tick is a smoke workload that exercises the core at the real control period: it
//! moves every joint about the middle of its range (`q_i = mid_i + 0.1 sin(t + 0.5 i)`), computes
//! the tool frame by forward kinematics and recovers the joints with tracking IK seeded with the
//! previous tick's solution, as the full controller will do for Cartesian commands. Statistics
//! are logged once per second.

use armgate_core::config::RobotConfig;
use armgate_core::kinematics::{Chain, IkResult, Joints};
use embassy_time::{Duration, Instant, Ticker};

/// Amplitude of the joint motion (rad or m).
const AMPLITUDE: f64 = 0.1;
/// Phase step between successive joints (rad).
const PHASE_STEP: f64 = 0.5;
/// Interval between two statistics lines.
const REPORT_INTERVAL: Duration = Duration::from_secs(1);

/// Counters over one report interval.
#[derive(Default)]
struct Stats {
    ticks: u32,
    converged: u32,
    not_converged: u32,
    errors: u32,
    iterations: u32,
    compute_us_total: u64,
    compute_us_max: u64,
    worst_position_error: f64,
}

/// The control period of `robot` as an embassy duration (whole microseconds, at least 1 µs).
pub fn period(robot: &RobotConfig) -> Duration {
    // The period is validated finite and positive; the cast saturates for absurd values.
    let micros = libm::round(robot.control_period * 1e6) as u64;
    Duration::from_micros(micros.max(1))
}

/// The control task: one tick every `robot.control_period`, forever.
#[embassy_executor::task]
pub async fn run(robot: &'static RobotConfig, chain: Chain) {
    let period = period(robot);
    defmt::info!(
        "control: {} ({} joints), period {} us",
        robot.name.as_str(),
        chain.dof(),
        period.as_micros()
    );
    let mid = chain.mid_range();
    let mut seed = mid;
    let mut stats = Stats::default();
    let start = Instant::now();
    let mut next_report = start + REPORT_INTERVAL;
    let mut ticker = Ticker::every(period);
    loop {
        ticker.next().await;
        let begin = Instant::now();
        let t = (begin - start).as_micros() as f64 * 1e-6;
        tick(robot, &chain, &mid, t, &mut seed, &mut stats);
        let compute = (Instant::now() - begin).as_micros();
        stats.compute_us_total += compute;
        stats.compute_us_max = stats.compute_us_max.max(compute);
        if begin >= next_report {
            report(&stats);
            stats = Stats::default();
            next_report += REPORT_INTERVAL;
        }
    }
}

/// One tick of the smoke workload: FK at the moving configuration, then tracking IK from `seed`.
fn tick(
    robot: &RobotConfig,
    chain: &Chain,
    mid: &Joints,
    t: f64,
    seed: &mut Joints,
    stats: &mut Stats,
) {
    stats.ticks += 1;
    let mut q = *mid;
    let mut phase = t;
    for v in q.iter_mut() {
        *v += AMPLITUDE * libm::sin(phase);
        phase += PHASE_STEP;
    }
    let target = match chain.forward(&q) {
        Ok(frame) => frame,
        Err(e) => {
            stats.errors += 1;
            defmt::warn!("control: FK refused: {}", defmt::Display2Format(&e));
            return;
        }
    };
    match chain.solve_tracking(&target, seed, &robot.ik) {
        Ok(result) => {
            let solution = result.solution();
            stats.iterations += solution.iterations;
            stats.worst_position_error = stats.worst_position_error.max(solution.position_error);
            match result {
                IkResult::Converged(_) => stats.converged += 1,
                IkResult::NotConverged(_) => stats.not_converged += 1,
            }
            *seed = solution.q;
        }
        Err(e) => {
            stats.errors += 1;
            defmt::warn!("control: IK refused: {}", defmt::Display2Format(&e));
        }
    }
}

/// Logs one statistics line.
fn report(stats: &Stats) {
    let ticks = u64::from(stats.ticks.max(1));
    defmt::info!(
        "control: {} ticks, {} converged, {} not converged, {} errors, {} IK iterations, worst position error {=f64} m, compute mean {} us max {} us",
        stats.ticks,
        stats.converged,
        stats.not_converged,
        stats.errors,
        stats.iterations,
        stats.worst_position_error,
        stats.compute_us_total / ticks,
        stats.compute_us_max
    );
}
