//! The measurements on every embedded robot: `libm`'s `sincos`, the core's `sqrt`, forward kinematics,
//! the Jacobian, joint rates (one damped least-squares solve), tracking IK (and, on a chain of
//! a closed-form family, Newton's tracking alone and the all-solutions closed form), and the
//! worst case of global IK (an unreachable target, which spends the whole budget).
//!
//! The samples follow the host benchmark (`core/examples/ik_bench.rs`, tracking mode) draw for
//! draw: the same generator and seed, a configuration uniform within the joint limits, its tool
//! frame as the target, and the seed `q + uniform(−0.1, 0.1)` per joint; so the first
//! [`SAMPLES`] targets and seeds are the host benchmark's first ones. Success means position and
//! orientation errors below 1e-5 (m, rad) and all joints within limits, as there.
//!
//! The arm's body (issue 35): one tick's check (`Body::check_tick`: the link frames and every
//! capsule against the boxes, the bounds and each other, at the commanded pose and where a stop
//! would end) at every configuration, with a random joint velocity up to each joint's limit;
//! and the up-front check of a joint move (`Body::check_path`) to a random goal within the
//! limits on the first [`LINE_CHECKS`].
//!
//! The up-front check of a Cartesian move (`Controller::move_cartesian`, which follows the
//! straight line to the goal by tracking IK before starting) is measured on the first
//! [`LINE_CHECKS`] configurations, each with a goal 2–60 cm and up to 1 rad away (drawn from a
//! generator of its own, distributed as in `core/examples/reach_bench.rs`); and the same checks
//! in slices of `LINE_SLICE` work as the cycle runs them (`Controller::plan_cartesian`, then
//! `continue_plan` a slice a tick): the row gives the instructions per slice, the first with
//! the check's start, and the number of slices.
//!
//! The up-front check of a joint move (`Controller::move_joints`: the tool's way, in pieces
//! halved until the arm cannot stray past a box or a bound unseen, `motion/joint_path.rs`) is
//! measured from the same configurations to the next one, and in its worst case: joint 1
//! turned 2 rad with the bounds' top 1 mm above the tool, which the way runs along, so that
//! the check spends its whole budget of FK evaluations and refuses (`near edge`).
//!
//! `KG` on a chain without a closed form (hybrid with its second slide moved to the third
//! joint, as `core/tests/kg_search.rs`) to an unreachable goal: its global search runs a slice
//! of at most `SEARCH_SLICE` Newton steps a tick; the row gives the instructions per slice,
//! mean and worst (the work a tick adds while the search runs), and the number of slices.

use core::hint::black_box;

use armgate_core::config::{RobotConfig, ValidRobot};
use armgate_core::cycle::{LINE_SLICE, SEARCH_SLICE};
use armgate_core::kinematics::{Chain, Family, Joints, Solutions};
use armgate_core::math::{self, Frame, Rotation3, Twist, Vector3};
use armgate_core::motion::{Body, Controller, Mode};
use armgate_core::rng::SplitMix64;
use cortex_m_semihosting::hprintln;

use crate::counter::{Counter, Timing, measure};

include!(concat!(env!("OUT_DIR"), "/robots.rs"));

/// The host benchmark's seed.
const SEED: u64 = 0x01C0_FFEE;
/// Random configurations per robot.
const SAMPLES: u32 = 200;
/// Seed perturbation of tracking IK, per joint (rad, or m for prismatic joints).
const PERTURBATION: f64 = 0.1;
/// Success threshold on position (m) and orientation (rad) error.
const SUCCESS_TOLERANCE: f64 = 1e-5;
/// Cartesian move checks per robot.
const LINE_CHECKS: u32 = 50;
/// Slices of a line's check at most (each spends at least one of its 64 tracking solves).
const MAX_LINE_SLICES: u32 = 100;
/// Seed of the move goals.
const LINE_SEED: u64 = 0x5EED_0016;

/// Everything measured on one robot.
#[derive(Default)]
struct Results {
    sincos: Timing,
    sqrt: Timing,
    forward: Timing,
    jacobian: Timing,
    joint_rates: Timing,
    tracking: Timing,
    newton_tracking: Timing,
    all_solutions: Timing,
    solutions: u64,
    line_check: Timing,
    lines_refused: u32,
    /// The same checks in slices of `LINE_SLICE` work, as the cycle runs them: one window a
    /// slice, the first with the check's start (what the tick handling a `BG` runs).
    line_slice: Timing,
    joint_path: Timing,
    joint_path_worst: Timing,
    worst_refused: bool,
    /// How far above the tool point the worst case's bounds were (m).
    grazing_clearance: f64,
    body_tick: Timing,
    body_path: Timing,
    paths_refused: u32,
    /// The most poses one joint move's check places (`Body::max_checks`).
    path_checks: u16,
    unreachable: Timing,
    unreachable_iterations: u32,
    iterations: u64,
    successes: u32,
    errors: u32,
}

/// Measures every embedded robot and prints the table; false if a robot could not be measured.
pub fn run(counter: &Counter) -> bool {
    counter.print_calibration();
    hprintln!(
        "{} samples per robot, seed {:#x}; instructions per call, mean (max)",
        SAMPLES,
        SEED
    );
    hprintln!(
        "| robot              | operation          | instructions/call     | mean iterations | success % |"
    );
    hprintln!(
        "|--------------------|--------------------|-----------------------|-----------------|-----------|"
    );
    let mut ok = true;
    for (name, bytes) in ROBOTS {
        if *name == "hybrid" {
            ok &= measure_search(bytes, counter);
        }
        let config = postcard::from_bytes::<RobotConfig>(bytes).ok();
        match config.map(RobotConfig::validate) {
            Some(Ok(config)) => {
                let results = measure_robot(&config);
                print_rows(name, &results, counter);
                ok &= results.errors == 0;
            }
            _ => {
                hprintln!(
                    "{}: the embedded description does not decode or validate",
                    name
                );
                ok = false;
            }
        }
    }
    ok
}

/// `KG`'s global search on hybrid without its closed form, to a goal 10 m out, slice by slice
/// as the cycle runs it: prints the instructions per slice; false if it cannot be measured.
fn measure_search(bytes: &[u8], counter: &Counter) -> bool {
    let config = postcard::from_bytes::<RobotConfig>(bytes).ok();
    let Some(Ok(config)) = config.map(|c| c.validate().and_then(|v| v.edit(|c| c.joints.swap(1, 2))))
    else {
        return false;
    };
    let chain = Chain::new(&config);
    let target = Frame::from_parts(Vector3::new(10.0, 0.0, 0.3).into(), Rotation3::identity());
    let Ok(mut search) = chain.global_search(&target, &chain.mid_range(), &config.ik, 0) else {
        return false;
    };
    let mut slices = Timing::default();
    let mut answer = None;
    // Every slice spends at least one step of the budget.
    for _ in 0..=config.ik.global_iterations {
        let (ticks, done) = measure(|| chain.continue_search(black_box(&mut search), SEARCH_SLICE));
        slices.add(ticks);
        if done.is_some() {
            answer = done;
            break;
        }
    }
    let (mean, max) = slices.instructions(counter);
    hprintln!(
        "| {:<18} | {:<18} | {:>9.0} ({:>9.0}) | {:>15} |         - |",
        "hybrid, numeric",
        "KG slice to 10 m",
        mean,
        max,
        slices.calls
    );
    chain.family().family == Family::Numeric && answer.is_some_and(|a| !a.is_converged())
}

fn measure_robot(config: &ValidRobot) -> Results {
    let chain = Chain::new(config);
    let mut body = Body::new(config);
    let mut results = Results {
        path_checks: body.max_checks(),
        ..Results::default()
    };
    let mut rng = SplitMix64::new(SEED);
    let mut goals = SplitMix64::new(LINE_SEED);
    let mut velocities = SplitMix64::new(BODY_SEED);
    let v_max = config.per_joint(|j| j.max_velocity);
    for sample in 0..SAMPLES {
        let q = chain.random_joints(&mut rng);

        let angle = q.first().copied().unwrap_or(0.0);
        let (ticks, _) = measure(|| libm::sincos(black_box(angle)));
        results.sincos.add(ticks);
        // The core's square root: the M7's VSQRT.F64 (libm's software one was about 110).
        let (ticks, _) = measure(|| armgate_core::math::sqrt(black_box(angle.abs() + 0.5)));
        results.sqrt.add(ticks);

        let (ticks, target) = measure(|| chain.forward(black_box(&q)));
        results.forward.add(ticks);
        let (ticks, jacobian) = measure(|| chain.jacobian(black_box(&q)));
        results.jacobian.add(ticks);
        // Joint rates = FK + J + one damped least-squares solve (the IK's step kernel).
        let twist = Twist::new(0.01, -0.02, 0.005, 0.02, 0.0, -0.01);
        let (ticks, _) = measure(|| chain.joint_rates(black_box(&q), &twist, 0.01, None));
        results.joint_rates.add(ticks);
        let (Ok(target), Ok(_)) = (target, jacobian) else {
            results.errors += 1;
            continue;
        };

        let mut v = v_max;
        for v in v.iter_mut() {
            *v *= velocities.uniform(-1.0, 1.0);
        }
        let (ticks, _) = measure(|| {
            black_box(&mut body).check_tick(&chain, black_box(&q), (&v, f64::INFINITY), None, false)
        });
        results.body_tick.add(ticks);

        if sample < LINE_CHECKS {
            check_line(config, &q, &target, &mut goals, &mut results);
            let next = chain.random_joints(&mut goals);
            check_joint_path(config, &q, &next, &mut results.joint_path);
            let to = chain.random_joints(&mut velocities);
            let (ticks, verdict) = measure(|| body.check_path(&chain, black_box(&q), &to));
            results.body_path.add(ticks);
            results.paths_refused += u32::from(verdict.is_err());
        }

        let mut seed = q;
        for v in seed.iter_mut() {
            *v += rng.uniform(-PERTURBATION, PERTURBATION);
        }
        if chain.family().family != Family::Numeric {
            let reference = chain.mid_range();
            // Into a list of the caller's, as the firmware would keep one (a returned list is
            // copied: 650 bytes).
            let mut all = Solutions::new();
            let (ticks, solved) = measure(|| {
                chain.solve_all_into(&target, black_box(&reference), black_box(&mut all))
            });
            results.all_solutions.add(ticks);
            results.solutions += solved.map_or(0, |()| all.len() as u64);
            let (ticks, _) =
                measure(|| chain.newton_tracking(&target, black_box(&seed), &config.ik));
            results.newton_tracking.add(ticks);
        }
        let (ticks, solved) =
            measure(|| chain.solve_tracking(&target, black_box(&seed), &config.ik));
        results.tracking.add(ticks);
        match solved {
            Ok(result) => {
                let solution = result.solution();
                results.iterations += u64::from(solution.iterations);
                if succeeded(&chain, &target, &solution.q) {
                    results.successes += 1;
                }
            }
            Err(_) => results.errors += 1,
        }
    }
    check_worst_joint_path(config, &chain, &mut results);
    // The worst case of a global solve: a target 10 m out is never reached, so every solve
    // spends the whole budget (`ik.global_iterations` Newton steps).
    for k in 0..UNREACHABLE_SAMPLES {
        let target = Frame::from_parts(
            Vector3::new(10.0, -0.5 * k as f64, 0.3).into(),
            Rotation3::identity(),
        );
        let seed = chain.mid_range();
        let (ticks, solved) =
            measure(|| chain.solve_global(&target, black_box(&seed), &config.ik, k));
        results.unreachable.add(ticks);
        match solved {
            Ok(result) if !result.is_converged() => {
                results.unreachable_iterations = result.solution().iterations;
            }
            _ => results.errors += 1,
        }
    }
    results
}

/// One up-front check of a Cartesian move from `q` (tool at `start`) to a random goal.
fn check_line(
    config: &ValidRobot,
    q: &Joints,
    start: &Frame,
    goals: &mut SplitMix64,
    results: &mut Results,
) {
    let mut ctrl = Controller::new(config);
    if ctrl.step(0.0, q).is_err() || ctrl.set_mode(Mode::Cartesian).is_err() {
        results.errors += 1;
        return;
    }
    let dir = random_direction(goals);
    let length = 0.02 + 0.58 * goals.next_f64();
    let turn = random_direction(goals);
    let goal = Frame::from_parts(
        (start.translation.vector + dir * (length / dir.norm())).into(),
        Rotation3::new(turn * goals.next_f64()) * start.rotation,
    );
    let (ticks, verdict) = measure(|| black_box(&mut ctrl).move_cartesian(black_box(goal), 0.0));
    results.line_check.add(ticks);
    results.lines_refused += u32::from(verdict.is_err());
    let mut ctrl = Controller::new(config);
    if ctrl.step(0.0, q).is_err() || ctrl.set_mode(Mode::Cartesian).is_err() {
        results.errors += 1;
        return;
    }
    let work = usize::from(LINE_SLICE);
    let (ticks, plan) = measure(|| {
        let mut plan = black_box(&ctrl).plan_cartesian(black_box(goal), 0.0).ok()?;
        let answer = black_box(&mut ctrl).continue_plan(&mut plan, work);
        Some((plan, answer))
    });
    results.line_slice.add(ticks);
    let Some((mut plan, mut answer)) = plan else {
        // Refused at once, as the one call was.
        results.errors += u32::from(verdict.is_ok());
        return;
    };
    // Each slice spends at least one point of the check's bounded number.
    for _ in 0..MAX_LINE_SLICES {
        if answer.is_some() {
            break;
        }
        let (ticks, next) = measure(|| black_box(&mut ctrl).continue_plan(&mut plan, work));
        results.line_slice.add(ticks);
        answer = next;
    }
    // The slices answer as the one call did.
    results.errors += u32::from(answer.map(|a| a.is_ok()) != Some(verdict.is_ok()));
}

/// One up-front check of a joint move from `q` to `goal`, timed into `timing`; whether it
/// was refused.
fn check_joint_path(config: &ValidRobot, q: &Joints, goal: &Joints, timing: &mut Timing) -> bool {
    let mut ctrl = Controller::new(config);
    if ctrl.step(0.0, q).is_err() || ctrl.set_mode(Mode::Joint).is_err() {
        return false;
    }
    let (ticks, verdict) = measure(|| black_box(&mut ctrl).move_joints(black_box(goal), 0.0));
    timing.add(ticks);
    verdict.is_err()
}

/// How far above the tool point the grazing bounds' top is tried: the tightest the controller
/// starts under (the bounds hold the tool's capsule, whose radius differs per robot).
const GRAZING_CLEARANCES: [f64; 6] = [0.001, 0.01, 0.02, 0.05, 0.1, 0.2];

/// The joint-path check's worst case: joint 1 turned 2 rad from the drives' home (the tool's
/// height does not change) under bounds whose top just clears the tool.
fn check_worst_joint_path(config: &ValidRobot, chain: &Chain, results: &mut Results) {
    let home = config.home();
    let Ok(tool) = chain.forward(&home) else {
        results.errors += 1;
        return;
    };
    let mut goal = home;
    if let (Some(q1), Some(max)) = (goal.get_mut(0), chain.max().first()) {
        *q1 = (*q1 + 2.0).min(*max);
    }
    for clearance in GRAZING_CLEARANCES {
        let top = tool.translation.vector.z + clearance;
        let Ok(grazed) = config.clone().edit(|c| {
            if let Some(z_max) = c.workspace.bounds.get_mut(5) {
                *z_max = top;
            }
        }) else {
            continue;
        };
        results.worst_refused =
            check_joint_path(&grazed, &home, &goal, &mut results.joint_path_worst);
        if results.joint_path_worst.calls > 0 {
            results.grazing_clearance = clearance;
            return;
        }
    }
}

/// A vector with components uniform in −0.5..0.5.
fn random_direction(rng: &mut SplitMix64) -> Vector3<f64> {
    Vector3::new(
        rng.next_f64() - 0.5,
        rng.next_f64() - 0.5,
        rng.next_f64() - 0.5,
    )
}

/// Seed of the body checks' joint velocities and joint-move goals.
const BODY_SEED: u64 = 0x0B0D_0035;

/// Global solves of unreachable targets per robot (each runs the whole budget).
const UNREACHABLE_SAMPLES: u64 = 3;

fn succeeded(chain: &Chain, target: &Frame, q: &Joints) -> bool {
    chain.forward(q).is_ok_and(|reached| {
        let d = math::diff(&reached, target);
        d.fixed_rows::<3>(0).norm() < SUCCESS_TOLERANCE
            && d.fixed_rows::<3>(3).norm() < SUCCESS_TOLERANCE
            && chain.within_limits(q)
    })
}

fn print_rows(name: &str, results: &Results, counter: &Counter) {
    let row = |operation: &str, timing: &Timing| {
        let (mean, max) = timing.instructions(counter);
        hprintln!(
            "| {:<18} | {:<18} | {:>9.0} ({:>9.0}) |               - |         - |",
            name,
            operation,
            mean,
            max
        );
    };
    row("libm::sincos", &results.sincos);
    row("sqrt (vsqrt.f64)", &results.sqrt);
    row("forward (FK)", &results.forward);
    row("jacobian (FK + J)", &results.jacobian);
    row("joint_rates (+DLS)", &results.joint_rates);
    let (mean, max) = results.tracking.instructions(counter);
    let calls = f64::from(results.tracking.calls.max(1));
    hprintln!(
        "| {:<18} | {:<18} | {:>9.0} ({:>9.0}) | {:>15.2} | {:>9.1} |",
        name,
        "tracking IK",
        mean,
        max,
        results.iterations as f64 / calls,
        100.0 * f64::from(results.successes) / calls
    );
    if results.all_solutions.calls > 0 {
        row("Newton tracking IK", &results.newton_tracking);
        let (mean, max) = results.all_solutions.instructions(counter);
        hprintln!(
            "| {:<18} | {:<18} | {:>9.0} ({:>9.0}) | {:>9.2} sols |         - |",
            name,
            "all solutions",
            mean,
            max,
            results.solutions as f64 / f64::from(results.all_solutions.calls)
        );
    }
    let (mean, max) = results.line_check.instructions(counter);
    hprintln!(
        "| {:<18} | {:<18} | {:>9.0} ({:>9.0}) |               - | {:>6.1} refused |",
        name,
        "Cartesian line check",
        mean,
        max,
        100.0 * f64::from(results.lines_refused) / f64::from(results.line_check.calls.max(1))
    );
    let (mean, max) = results.line_slice.instructions(counter);
    hprintln!(
        "| {:<18} | {:<18} | {:>9.0} ({:>9.0}) | {:>15} |         - |",
        name,
        "line check slice",
        mean,
        max,
        results.line_slice.calls
    );
    let (mean, max) = results.joint_path.instructions(counter);
    hprintln!(
        "| {:<18} | {:<18} | {:>9.0} ({:>9.0}) |               - |         - |",
        name,
        "joint path check",
        mean,
        max
    );
    let (mean, _) = results.joint_path_worst.instructions(counter);
    if results.joint_path_worst.calls == 0 {
        // The controller refused to start at home under every grazing bounds tried: nothing
        // was timed.
        hprintln!(
            "| {:<18} | {:<18} | not measured: the controller refuses home under every tried bounds |",
            name,
            "joint path worst"
        );
    } else {
        hprintln!(
            "| {:<18} | {:<18} | {:>9.0} ({:>9.0}) |               - | {:>9} |",
            name,
            "joint path worst",
            mean,
            mean,
            if results.worst_refused { "refused" } else { "passed" }
        );
        hprintln!(
            "{}: the worst joint path is checked under bounds {:.0} mm above the tool point",
            name,
            results.grazing_clearance * 1000.0
        );
    }
    row("body check, tick", &results.body_tick);
    let (mean, max) = results.body_path.instructions(counter);
    hprintln!(
        "| {:<18} | {:<18} | {:>9.0} ({:>9.0}) |               - | {:>6.1} refused |",
        name,
        "body check, jB",
        mean,
        max,
        100.0 * f64::from(results.paths_refused) / f64::from(results.body_path.calls.max(1))
    );
    // The check's worst case: its poses are capped (each costs about what one pose of the
    // tick's check costs, and the sweep bounds of every gap).
    hprintln!(
        "| {:<18} | {:<18} | {:>9} poses at most |               - |         - |",
        name,
        "body check, jB cap",
        results.path_checks
    );
    let (mean, max) = results.unreachable.instructions(counter);
    hprintln!(
        "| {:<18} | {:<18} | {:>9.0} ({:>9.0}) | {:>15} |         - |",
        name,
        "global unreachable",
        mean,
        max,
        results.unreachable_iterations
    );
    if results.errors > 0 {
        hprintln!("{}: {} calls refused", name, results.errors);
    }
}
