//! The seed thesis's simulation experiments (spec §8.2, E7–E9) on the controller with an ideal
//! arm. Shared by `tests/experiments.rs` (asserts the goals) and `examples/seed_experiments.rs`
//! (prints the table).
#![allow(
    dead_code,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::approx_constant
)]

use std::f64::consts::PI;

use armgate_core::config::ValidRobot;
use armgate_core::kinematics::{Chain, IkResult, Joints};
use armgate_core::math::{Frame, Rotation3, Vector3};
use armgate_core::motion::{Controller, Mode, StepOutput};
use armgate_core::sim::IdealArm;

/// The rectangle of E8/E9 (m), closed: the last point is the first.
pub const RECTANGLE: [[f64; 3]; 5] = [
    [0.5, 0.2, 0.1],
    [0.5, 0.2, 0.4],
    [0.5, -0.2, 0.4],
    [0.5, -0.2, 0.1],
    [0.5, 0.2, 0.1],
];

/// One tick of a run, kept for the plots of `examples/seed_experiments.rs`.
#[derive(Clone, Copy, Debug)]
pub struct TraceTick {
    /// Time (s).
    pub t: f64,
    /// Tool position (m).
    pub tool: Vector3<f64>,
    /// The run's error measure at this tick (m): distance from the leg's line (E8/E9) or from
    /// the unreachable goal (E7).
    pub error: f64,
    /// The IK divergence guard fired (WN22).
    pub diverging: bool,
    /// The Cartesian set-point's position (m; the tool's if none).
    pub setpoint: Vector3<f64>,
}

impl TraceTick {
    /// The tick at `t` with output `out`, the tool at `tool` and the run's error `error`.
    fn new(t: f64, out: &StepOutput, tool: Vector3<f64>, error: f64) -> Self {
        Self {
            t,
            tool,
            error,
            diverging: out.events.ik_divergence,
            setpoint: out.setpoint.map_or(tool, |f| f.translation.vector),
        }
    }
}

/// One control tick with an ideal arm: the output, the new joints and the largest joint step.
fn tick(ctrl: &mut Controller, arm: &mut IdealArm, now: f64) -> (StepOutput, Joints, f64) {
    let before = arm.measured();
    let out = ctrl.step(now, &before).unwrap();
    arm.step(out.command.as_ref());
    let q = arm.measured();
    let step = q
        .iter()
        .zip(before.iter())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    (out, q, step)
}

/// Results of a rectangle run.
#[derive(Debug)]
pub struct RectangleRun {
    /// The constant tool orientation used (roll, pitch, yaw).
    pub rpy: [f64; 3],
    /// Mean and maximum distance of the tool from the current leg's line (m).
    pub mean_error: f64,
    /// Maximum of the same (m).
    pub max_error: f64,
    /// Time of the maximum (s).
    pub max_error_time: f64,
    /// Largest joint change in one tick (rad or m).
    pub max_joint_step: f64,
    /// Duration of the whole run (s).
    pub duration: f64,
    /// Joints at the start and at the end.
    pub first_joints: Joints,
    /// Joints at the end.
    pub last_joints: Joints,
    /// Ticks with an IK divergence event.
    pub divergence_ticks: usize,
    /// Every tick.
    pub trace: Vec<TraceTick>,
}

/// The experiment's settings: v_max 0.05 m/s, a_max 0.10 m/s² on translation (spec §8.2 E8),
/// no rate limit in the way (the seed enforced none in position mode).
pub fn rectangle_config(config: ValidRobot) -> ValidRobot {
    config
        .edit(|config| {
            config.cartesian.max_velocity = [0.05, 0.05, 0.05, 0.1, 0.1, 0.1];
            config.cartesian.max_acceleration = [0.10, 0.10, 0.10, 0.2, 0.2, 0.2];
            for j in config.joints.iter_mut() {
                j.max_rate = 100.0;
                j.drive.max_speed = 100.0;
            }
            config.workspace.boxes.clear();
        })
        .unwrap()
}

/// Candidate "level" tool orientations (roll, pitch, yaw); the first that the arm reaches at
/// every corner is used.
const LEVEL_ORIENTATIONS: [[f64; 3]; 6] = [
    [0.0, PI / 2.0, 0.0],
    [PI, 0.0, 0.0],
    [0.0, 0.0, 0.0],
    [0.0, -PI / 2.0, 0.0],
    [PI / 2.0, 0.0, 0.0],
    [-PI / 2.0, 0.0, 0.0],
];

fn corner(rot: Rotation3<f64>, p: [f64; 3]) -> Frame {
    Frame::from_parts(Vector3::from(p).into(), rot)
}

/// Runs the rectangle as a Cartesian via-point sequence and measures the kinematic error: the
/// distance from the tool to the line through the previous and the next waypoint, every tick.
pub fn run_rectangle(config: &ValidRobot) -> RectangleRun {
    let chain = Chain::new(config);
    let mid = chain.mid_range();
    let (rpy, start) = LEVEL_ORIENTATIONS
        .iter()
        .find_map(|rpy| {
            let rot = Rotation3::from_euler_angles(rpy[0], rpy[1], rpy[2]);
            let mut first = None;
            for (k, p) in RECTANGLE.iter().enumerate() {
                match chain
                    .solve_global(&corner(rot, *p), &mid, &config.ik, k as u64)
                    .unwrap()
                {
                    IkResult::Converged(s) => first = first.or(Some(s.q)),
                    IkResult::NotConverged(_) => return None,
                }
            }
            Some((*rpy, first?))
        })
        .expect("no level orientation reaches every corner");
    let rot = Rotation3::from_euler_angles(rpy[0], rpy[1], rpy[2]);

    let mut ctrl = Controller::new(config);
    let mut arm = IdealArm::new(start);
    let period = config.control_period;
    let mut now = 0.0;
    ctrl.step(now, &arm.measured()).unwrap();
    ctrl.set_mode(Mode::Cartesian).unwrap();
    for (k, p) in RECTANGLE.iter().enumerate().skip(1) {
        ctrl.set_cartesian_via(k - 1, corner(rot, *p), 0.0).unwrap();
    }
    ctrl.start_cartesian_sequence().unwrap();

    let (mut leg, mut sum, mut count) = (0usize, 0.0, 0usize);
    let mut run = RectangleRun {
        rpy,
        mean_error: 0.0,
        max_error: 0.0,
        max_error_time: 0.0,
        max_joint_step: 0.0,
        duration: 0.0,
        first_joints: start,
        last_joints: start,
        divergence_ticks: 0,
        trace: Vec::new(),
    };
    for _ in 0..100_000 {
        now += period;
        let (out, q, step) = tick(&mut ctrl, &mut arm, now);
        run.max_joint_step = run.max_joint_step.max(step);
        run.divergence_ticks += usize::from(out.events.ik_divergence);
        let p = chain.forward(&q).unwrap().translation.vector;
        let (a, b) = (
            Vector3::from(RECTANGLE[leg]),
            Vector3::from(RECTANGLE[leg + 1]),
        );
        let e = (p - a).cross(&(b - a)).norm() / (b - a).norm();
        run.trace.push(TraceTick::new(now, &out, p, e));
        sum += e;
        count += 1;
        if e > run.max_error {
            run.max_error = e;
            run.max_error_time = now;
        }
        if (p - b).norm() < 1e-7 && leg + 2 < RECTANGLE.len() {
            leg += 1;
        }
        if out.events.sequence_finished || out.events.sequence_aborted {
            assert!(
                out.events.sequence_finished,
                "sequence aborted at leg {leg}"
            );
            break;
        }
    }
    run.mean_error = sum / count as f64;
    run.duration = now;
    run.last_joints = arm.measured();
    run
}

/// How closely the tool passes each intermediate corner of the rectangle (m): the smallest
/// distance over the run, for corners 1, 2, 3.
pub fn corner_passes(run: &RectangleRun) -> [f64; 3] {
    let mut passes = [f64::INFINITY; 3];
    for (pass, corner) in passes.iter_mut().zip(&RECTANGLE[1..4]) {
        let corner = Vector3::from(*corner);
        for tick in &run.trace {
            *pass = pass.min((tick.tool - corner).norm());
        }
    }
    passes
}

/// Distance from `p` to the rectangle's edges (m).
pub fn off_rectangle(p: &Vector3<f64>) -> f64 {
    RECTANGLE
        .windows(2)
        .map(|w| {
            let (a, b) = (Vector3::from(w[0]), Vector3::from(w[1]));
            let d = b - a;
            let s = ((p - a).dot(&d) / d.norm_squared()).clamp(0.0, 1.0);
            (p - (a + d * s)).norm()
        })
        .fold(f64::INFINITY, f64::min)
}

/// The rectangle config with a default Cartesian blend tolerance (m + rad).
pub fn blended(config: ValidRobot, tolerance: f64) -> ValidRobot {
    config
        .edit(|config| config.blend.cartesian = tolerance)
        .unwrap()
}

/// Jerk limits for the rectangle with jerk-limited profiles: 0.2 m/s³ on translation (0.5 s
/// to the 0.1 m/s² limit), 0.5 rad/s³ on rotation, 5 rad/s³ (m/s³) on the joints.
pub const RECTANGLE_JERK: [f64; 6] = [0.2, 0.2, 0.2, 0.5, 0.5, 0.5];

/// The rectangle config with jerk-limited profiles ([`RECTANGLE_JERK`]).
pub fn jerk_limited(config: ValidRobot) -> ValidRobot {
    config
        .edit(|config| {
            config.motion.profile = armgate_core::config::ProfileKind::JerkLimited;
            config.cartesian.max_jerk = Some(RECTANGLE_JERK);
            for j in config.joints.iter_mut() {
                j.max_jerk = Some(5.0);
            }
        })
        .unwrap()
}

/// Results of the divergence-guard run.
#[derive(Debug)]
pub struct DivergenceRun {
    /// Tool position at the end (m).
    pub final_position: Vector3<f64>,
    /// Distance from the unreachable goal at the end (m).
    pub final_distance: f64,
    /// Largest increase of the distance to the goal between two ticks during the last leg (m).
    pub worst_retreat: f64,
    /// Sum of all such increases during the last leg (m).
    pub total_retreat: f64,
    /// Ticks with an IK divergence event.
    pub divergence_ticks: usize,
    /// Largest joint change in one tick (rad).
    pub max_joint_step: f64,
    /// Distance from the shoulder (joint-2 origin) to the tool at the end, and the arm's reach.
    pub extension: (f64, f64),
    /// The sequence's via points (m), the last the unreachable goal.
    pub waypoints: [Vector3<f64>; 3],
    /// Every tick.
    pub trace: Vec<TraceTick>,
}

/// The unreachable goal of thesis Fig. 3.2.
pub const UNREACHABLE: [f64; 3] = [-0.5, 4.0, 0.7];

/// E7: ranger-mk1, with its deployed generator limits, runs a short sequence whose last point is
/// out of reach. The workspace bounds are widened so that the goal reaches the generator, and the
/// up-front line check is off (it refuses the sequence, see `ik.check_lines`), as in the
/// thesis's simulation.
pub fn run_divergence(config: &ValidRobot) -> DivergenceRun {
    let config = config
        .clone()
        .edit(|config| {
            config.workspace.bounds = [-5.0, 5.0, -5.0, 5.0, -5.0, 5.0];
            config.ik.check_lines = false;
        })
        .unwrap();
    let chain = Chain::new(&config);
    let start = Joints::from_slice(&[1.5708, 0.6, -0.4, 0.2, 1.8, 0.1]).unwrap();
    let mut ctrl = Controller::new(&config);
    let mut arm = IdealArm::new(start);
    let period = config.control_period;
    let mut now = 0.0;
    ctrl.step(now, &arm.measured()).unwrap();
    ctrl.set_mode(Mode::Cartesian).unwrap();
    let home = chain.forward(&start).unwrap();
    let waypoints = [
        home.translation.vector + Vector3::new(0.1, 0.0, 0.0),
        home.translation.vector + Vector3::new(0.1, 0.1, -0.1),
        Vector3::from(UNREACHABLE),
    ];
    for (k, p) in waypoints.iter().enumerate() {
        ctrl.set_cartesian_via(k, Frame::from_parts((*p).into(), home.rotation), 0.0)
            .unwrap();
    }
    ctrl.start_cartesian_sequence().unwrap();
    let goal = Vector3::from(UNREACHABLE);
    let mut run = DivergenceRun {
        final_position: Vector3::zeros(),
        final_distance: 0.0,
        worst_retreat: 0.0,
        total_retreat: 0.0,
        divergence_ticks: 0,
        max_joint_step: 0.0,
        extension: (0.0, 0.0),
        waypoints,
        trace: Vec::new(),
    };
    let mut last_leg = false;
    let mut prev_distance = f64::INFINITY;
    // Long enough for the set-point to travel ~4 m at 0.03 m/s and the sequence to give up.
    for _ in 0..((400.0 / period) as usize) {
        now += period;
        let (out, q, step) = tick(&mut ctrl, &mut arm, now);
        run.max_joint_step = run.max_joint_step.max(step);
        run.divergence_ticks += usize::from(out.events.ik_divergence);
        let p = chain.forward(&q).unwrap().translation.vector;
        last_leg |= (p - waypoints[1]).norm() < 1e-6;
        let distance = (p - goal).norm();
        run.trace.push(TraceTick::new(now, &out, p, distance));
        if last_leg {
            run.worst_retreat = run.worst_retreat.max(distance - prev_distance);
            run.total_retreat += (distance - prev_distance).max(0.0);
        }
        prev_distance = distance;
        run.final_position = p;
        run.final_distance = distance;
        if out.events.sequence_aborted || out.events.sequence_finished {
            break;
        }
    }
    let mut links = [Frame::identity(); armgate_core::MAX_JOINTS];
    chain.link_frames(&arm.measured(), &mut links).unwrap();
    let shoulder = links[1].translation.vector;
    let j = &config.joints;
    let reach =
        (j[2].a.powi(2) + 0.0).sqrt() + (j[3].a.powi(2) + j[3].d.powi(2)).sqrt() + config.tool.d;
    run.extension = ((run.final_position - shoulder).norm(), reach);
    run
}
