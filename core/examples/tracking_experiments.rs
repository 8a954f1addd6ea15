//! The seed thesis's tracking experiments E5 (circle, Table 4.3) and E6 (sinusoids along x and
//! z, Tables 4.4 and 4.5) on ranger-mk1 with simulated Elmo Whistle drives (spec §4.5, §8.1,
//! §8.2), printed next to the seed's measurements.
//!
//! ```sh
//! cargo run --release -p armgate-core --example tracking_experiments [-- --plots DIR]
//! cargo run --release -p armgate-core --example tracking_experiments -- --pdo 500000
//! ```
//!
//! With `--pdo BITRATE`, the drives stream on the PDO schedule at the fastest period it
//! carries at that bit rate under 70 % load (4.32 ms at 500 kbit/s, 2.16 ms at 1 Mbit/s)
//! instead of the robot file's 19.44 ms on the interpreter schedule.
//!
//! With `--plots DIR`, writes one SVG per row (`e5-circle-T5.svg`, `e6-sin-x-T2.svg`, ...) for
//! the chosen start pose: the path (the circle's plane, or the sinusoid's axis over time)
//! ideal, commanded and as the drives followed it at both speed limits, and the drives'
//! distance from the ideal point over time at the fitted delay.
//!
//! Each shape runs for 8 periods in the full control loop (controller, drive manager, PT
//! streaming over the virtual CAN bus at the robot file's period and bit rate, simulated
//! Whistles), then `finish_shape`. Three errors are reported per row:
//!
//! * commanded path: FK of the controller's joint command each tick against the ideal shape
//!   point at the same phase (no delay to fit: command `k` after the start is phase `k · period`);
//! * drives at 0.9 rad/s (the Whistle limit the thesis observed) and at 5 rad/s: FK of the
//!   simulated drives' actual joint positions against the ideal shape point, the time aligned by
//!   the constant delay that minimises the sum of squared distances (the thesis's least-squares
//!   phase fit; spec §8.1). d̄ and S are the spec's mean and sample standard deviation over the
//!   8 cycles of drive time, start-up transient included.
//!
//! Every shape starts with the tool at (0, 0.62, 0.52) m. The thesis does not give the start
//! orientation; candidates (the orientation of a comfortable forward pose, level with the tool
//! pointing forward, tool pointing down), each solved by global IK from a few seeds, are tried
//! in order, and the first whose every shape runs on an ideal arm with no IK, joint-limit or
//! rate event is used. The next one that qualifies is printed too, for comparison: the joint
//! speeds, and so what the 0.9 rad/s limit does, depend on the pose. docs/drives.md discusses
//! the results.
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::approx_constant // the seed's home angle 1.5708, as it wrote it
)]

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

#[path = "../tests/drives_rig/mod.rs"]
mod drives_rig;
use drives_rig::Rig;

use armgate_core::config::bus_load::DEFAULT_CEILING;
use armgate_core::config::{Streaming, ValidRobot, load_file};
use armgate_core::drives::DriveSettings;
use armgate_core::kinematics::{Chain, IkResult, Joints};
use armgate_core::math::{self, Frame, Rotation3, Vector3};
use armgate_core::motion::{Controller, Mode, Shape};
use armgate_core::sim::IdealArm;
use armgate_core::sim::{SimWhistle, VirtualBus, WhistleConfig};
use armgate_plot::{Figure, Panel, Series, write_svg};

/// The start pose's position (m): the sinusoids' centre (spec §4.5), and the circles' start.
const START: [f64; 3] = [0.0, 0.62, 0.52];
/// A comfortable forward pose of ranger-mk1; its tool orientation is the first candidate and
/// it seeds the IK of the start pose.
const COMFORT: [f64; 6] = [1.5708, 0.6, -0.4, 0.2, 1.8, 0.1];
/// Seeds of the start pose's global IK: the comfortable pose, then upper arm near vertical,
/// forearm forward, wrist rolls at zero.
const IK_SEEDS: [[f64; 6]; 2] = [COMFORT, [-1.5708, 1.3, 1.0, 0.0, 2.5, 0.0]];
/// Motion cycles per run (the thesis averaged over 8).
const CYCLES: f64 = 8.0;
/// Joint rate limit for the experiment (rad/s): the seed enforced none in position mode.
const JOINT_RATE: f64 = 10.0;
/// The Whistle speed limit the thesis observed (rad/s), and a raised one.
const DRIVE_SPEEDS: [f64; 2] = [0.9, 5.0];
/// Delays tried in the phase fit (s): a grid of this step up to this maximum, then refined.
const DELAY_STEP: f64 = 0.002;
const DELAY_MAX: f64 = 1.0;

/// One row of Tables 4.3–4.5.
struct Experiment {
    table: &'static str,
    shape: Shape,
    /// The seed's measured d̄ and S (mm).
    seed: (f64, f64),
}

fn experiments() -> Vec<Experiment> {
    let mut rows = Vec::new();
    for (period, seed) in [
        (5.0, (42.0, 20.0)),
        (7.0, (4.7, 2.3)),
        (10.0, (4.0, 0.9)),
        (15.0, (3.9, 0.9)),
        (20.0, (3.8, 0.9)),
    ] {
        rows.push(Experiment {
            table: "E5 circle",
            shape: Shape::Circle {
                radius: 0.20,
                period,
                axis_i: 0,
                axis_j: 2,
            },
            seed,
        });
    }
    for (period, seed) in [
        (2.0, (37.0, 15.0)),
        (3.0, (21.0, 11.0)),
        (5.0, (2.9, 1.9)),
        (8.0, (2.6, 1.3)),
        (10.0, (2.6, 1.2)),
        (15.0, (2.6, 1.2)),
    ] {
        rows.push(Experiment {
            table: "E6 sin x",
            shape: Shape::Sinusoid {
                amplitude: 0.10,
                period,
                axis: 0,
            },
            seed,
        });
    }
    for (period, seed) in [
        (1.0, (23.0, 11.0)),
        (2.0, (3.4, 1.1)),
        (3.0, (3.8, 0.8)),
        (5.0, (3.7, 0.9)),
        (8.0, (3.7, 1.1)),
        (10.0, (3.7, 0.9)),
    ] {
        rows.push(Experiment {
            table: "E6 sin z",
            shape: Shape::Sinusoid {
                amplitude: 0.10,
                period,
                axis: 2,
            },
            seed,
        });
    }
    rows
}

fn shape_period(shape: &Shape) -> f64 {
    match *shape {
        Shape::Circle { period, .. } | Shape::Sinusoid { period, .. } => period,
    }
}

/// Peak tool speed (m/s): 2πR/T for the circle, 2πK/T for the sinusoid.
fn shape_speed(shape: &Shape) -> f64 {
    match *shape {
        Shape::Circle { radius, period, .. } => 2.0 * PI * radius / period,
        Shape::Sinusoid {
            amplitude, period, ..
        } => 2.0 * PI * amplitude / period,
    }
}

/// The experiment's robot: ranger-mk1 with every joint's rate limit raised.
fn config() -> ValidRobot {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../robots/ranger-mk1.toml");
    let args: Vec<String> = std::env::args().collect();
    let pdo: Option<u32> = args.iter().position(|a| a == "--pdo").map(|i| {
        args.get(i + 1)
            .and_then(|b| b.parse().ok())
            .expect("--pdo BITRATE")
    });
    let config = load_file(&path)
        .expect("robot file")
        .edit(|config| {
            for joint in config.joints.iter_mut() {
                joint.max_rate = JOINT_RATE;
                joint.drive.max_speed = JOINT_RATE;
            }
        })
        .expect("valid with the raised rate");
    let Some(bitrate) = pdo else { return config };
    let pdo = config
        .edit(|config| {
            config.drives.streaming = Streaming::Pdo;
            config.drives.can_bitrate = bitrate;
        })
        .expect("the PDO schedule at the seed's period");
    let fastest = DriveSettings::default()
        .load_model(&pdo)
        .fastest_period(bitrate, DEFAULT_CEILING)
        .expect("a period under the ceiling");
    pdo.edit(|config| config.control_period = fastest.period)
        .expect("the fastest period keeps under the ceiling")
}

/// A start pose: how its orientation was chosen, the orientation and the joints.
struct StartPose {
    name: &'static str,
    rot: Rotation3<f64>,
    q: Joints,
}

fn main() {
    let plots = armgate_plot::plots_dir_from_args().unwrap();
    let config = config();
    let chain = Chain::new(&config);
    let rows = experiments();
    println!(
        "ranger-mk1: control period {:.2} ms ({:.2} Hz), CAN {} kbit/s, 6 simulated Whistles (PT streaming, {:?} schedule); joint max_rate raised to {JOINT_RATE} rad/s",
        config.control_period * 1e3,
        1.0 / config.control_period,
        config.drives.can_bitrate / 1000,
        config.drives.streaming
    );
    println!(
        "every shape starts with the tool at {START:?} m (the circle's centre is 0.20 m along −x, at (−0.20, 0.62, 0.52)); {CYCLES} periods, then finish_shape"
    );
    println!(
        "drive error: constant delay τ fitted by least squares (grid {:.0} ms up to {:.0} ms, then golden section); d̄ and S over 8 periods of drive time from the start (start-up transient included)",
        DELAY_STEP * 1e3,
        DELAY_MAX * 1e3
    );
    let poses = start_poses(&config, &chain, &rows);
    let main = poses
        .first()
        .expect("no candidate start pose runs every shape");
    print_table(&config, &chain, &rows, main, plots.as_deref());
    if let Some(other) = poses.get(1) {
        println!("\nFor comparison, the next candidate that runs every shape:");
        print_table(&config, &chain, &rows, other, None);
    }
}

/// Prints the table for one start pose; with `plots`, writes each row's figure there.
fn print_table(
    config: &ValidRobot,
    chain: &Chain,
    rows: &[Experiment],
    pose: &StartPose,
    plots: Option<&Path>,
) {
    println!(
        "\nstart orientation {} (tool z axis {:.3?}, rpy {:.4?}), joints {:.4?}\n",
        pose.name,
        (pose.rot * Vector3::z()).as_slice(),
        math::rpy(&pose.rot),
        &pose.q[..]
    );
    println!(
        "| exp | T (s) | v (mm/s) | seed d̄ / S (mm) | peak commanded joint speed (rad/s); joints > 0.9 | commanded path mean / max (mm) | drives 0.9 rad/s: τ (ms), d̄ / S (mm) | drives 5 rad/s: τ (ms), d̄ / S (mm) | PT underflows / overruns |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for row in rows {
        let runs: Vec<Run> = DRIVE_SPEEDS
            .iter()
            .map(|&speed| run(config, chain, &pose.q, &row.shape, speed))
            .collect();
        for r in &runs {
            assert!(
                r.notes.is_empty(),
                "{} T = {}: {}",
                row.table,
                shape_period(&row.shape),
                r.notes.join("; ")
            );
        }
        let first = &runs[0];
        let (mut peak, mut peak_joint) = (0.0, 0);
        let mut fast = Vec::new();
        for (j, &v) in first.peak.iter().enumerate() {
            if v > peak {
                (peak, peak_joint) = (v, j);
            }
            if v > DRIVE_SPEEDS[0] {
                fast.push(format!("J{} {v:.2}", j + 1));
            }
        }
        let fast = if fast.is_empty() {
            "none".to_owned()
        } else {
            fast.join(", ")
        };
        let health = runs
            .iter()
            .fold((0, 0), |(u, o), r| (u + r.underflows, o + r.overruns));
        let drive = |r: &Run| {
            format!(
                "{:.0}, {:.2} / {:.2}",
                r.delay * 1e3,
                r.track_mean * 1e3,
                r.track_s * 1e3
            )
        };
        println!(
            "| {} | {} | {:.0} | {:.1} / {:.1} | {:.2} (J{}); {} | {:.1e} / {:.1e} | {} | {} | {} / {} |",
            row.table,
            shape_period(&row.shape),
            shape_speed(&row.shape) * 1e3,
            row.seed.0,
            row.seed.1,
            peak,
            peak_joint + 1,
            fast,
            first.cmd_mean * 1e3,
            first.cmd_max * 1e3,
            drive(&runs[0]),
            drive(&runs[1]),
            health.0,
            health.1,
        );
        if let Some(dir) = plots {
            plot_row(dir, row, &runs);
        }
    }
}

/// The file name of a row's figure, e.g. `e5-circle-T5.svg`.
fn figure_name(row: &Experiment) -> String {
    let slug = row.table.to_lowercase().replace(' ', "-");
    format!("{slug}-T{}.svg", shape_period(&row.shape))
}

/// A row's figure: the path (the circle's x–z plane, or the sinusoid's axis over time),
/// ideal, commanded and at each drive speed; and each drive run's distance from the ideal
/// point at its fitted delay.
fn plot_row(dir: &Path, row: &Experiment, runs: &[Run]) {
    let Some(first) = runs.first() else { return };
    let ideal = |s: f64| ideal(first.origin, &row.shape, s, first.end);
    let drives = |r: &Run| format!("drives at {:.1} rad/s", r.drive_speed);
    let path = match row.shape {
        Shape::Circle { .. } => {
            let xz = |p: Vector3<f64>| (p.x, p.z);
            let mut panel =
                Panel::new("the path in the x–z plane", "x (m)", "z (m)").equal_aspect();
            for (k, r) in runs.iter().enumerate() {
                panel = panel.series(
                    Series::line(drives(r), r.drive_path.iter().map(|(_, p)| xz(*p))).color(k + 2),
                );
            }
            let n = 720;
            let period = shape_period(&row.shape);
            panel
                .series(
                    Series::line("commanded", first.commanded.iter().map(|(_, p)| xz(*p))).color(1),
                )
                .series(
                    Series::reference(
                        "ideal",
                        (0..=n).map(|k| xz(ideal(f64::from(k) / f64::from(n) * period))),
                    )
                    .color(0),
                )
        }
        Shape::Sinusoid { axis, .. } => {
            let axis = usize::from(axis);
            let name = ["x", "y", "z"].get(axis).copied().unwrap_or("?");
            let along =
                move |p: Vector3<f64>| [p.x, p.y, p.z].get(axis).copied().unwrap_or(f64::NAN);
            let mut panel = Panel::new(
                format!("{name} over time (the other axes held)"),
                "t (s)",
                format!("{name} (m)"),
            );
            for (k, r) in runs.iter().enumerate() {
                panel = panel.series(
                    Series::line(drives(r), r.drive_path.iter().map(|(t, p)| (*t, along(*p))))
                        .color(k + 2),
                );
            }
            panel
                .series(
                    Series::line(
                        "commanded",
                        first.commanded.iter().map(|(t, p)| (*t, along(*p))),
                    )
                    .color(1),
                )
                .series(
                    Series::reference(
                        "ideal",
                        first.commanded.iter().map(|(t, _)| (*t, along(ideal(*t)))),
                    )
                    .color(0),
                )
        }
    };
    let mut error = Panel::new(
        "distance from the ideal point, drive time shifted by the fitted delay τ",
        "t (s)",
        "distance (mm)",
    );
    for (k, r) in runs.iter().enumerate() {
        error = error.series(
            Series::line(
                format!(
                    "{}: τ = {:.0} ms, d̄ = {:.2} mm, S = {:.2} mm",
                    drives(r),
                    r.delay * 1e3,
                    r.track_mean * 1e3,
                    r.track_s * 1e3
                ),
                r.drive_path
                    .iter()
                    .map(|(t, p)| (*t, (*p - ideal(t - r.delay)).norm() * 1e3)),
            )
            .color(k + 2),
        );
    }
    let title = format!(
        "{} T = {} s ({:.0} mm/s), ranger-mk1, {} cycles; seed: d̄ = {} mm, S = {} mm",
        row.table,
        shape_period(&row.shape),
        shape_speed(&row.shape) * 1e3,
        CYCLES,
        row.seed.0,
        row.seed.1
    );
    let figure = Figure::new(title, vec![path, error])
        .columns(2)
        .panel_size(640, 520);
    let file = dir.join(figure_name(row));
    write_svg(&file, &figure).unwrap();
    println!("wrote {}", file.display());
}

/// Candidate start poses, in order: each orientation solved by global IK from each seed; the
/// ones whose every shape runs through the controller (ideal arm) with no IK, joint-limit,
/// rate or workspace event. Prints why the others were passed over.
fn start_poses(config: &ValidRobot, chain: &Chain, rows: &[Experiment]) -> Vec<StartPose> {
    let orientations = [
        (
            "of the comfortable pose (1.5708, 0.6, -0.4, 0.2, 1.8, 0.1)",
            chain.forward(&COMFORT).unwrap().rotation,
        ),
        (
            "level, tool pointing forward (+y)",
            Rotation3::from_euler_angles(0.0, PI / 2.0, PI / 2.0),
        ),
        (
            "tool pointing down",
            Rotation3::from_euler_angles(PI, 0.0, 0.0),
        ),
    ];
    let mut found = Vec::new();
    for (name, rot) in orientations {
        let target = Frame::from_parts(Vector3::from(START).into(), rot);
        let mut tried: Vec<Joints> = Vec::new();
        for seed in IK_SEEDS {
            let Ok(IkResult::Converged(s)) = chain.solve_global(&target, &seed, &config.ik, 1)
            else {
                continue;
            };
            let same = |q: &Joints| q.iter().zip(s.q.iter()).all(|(a, b)| (a - b).abs() < 1e-6);
            if tried.iter().any(same) {
                continue;
            }
            tried.push(s.q);
            match rows.iter().find_map(|row| {
                dry_run(config, chain, &s.q, &row.shape)
                    .err()
                    .map(|e| (row, e))
            }) {
                None => {
                    found.push(StartPose { name, rot, q: s.q });
                    break;
                }
                Some((row, why)) => println!(
                    "passed over: orientation {name}, joints {:.3?}: {} T = {} s: {why}",
                    &s.q[..],
                    row.table,
                    shape_period(&row.shape)
                ),
            }
        }
    }
    found
}

/// Runs a shape on an ideal arm: `Ok(peak commanded joint speeds)` if it completes with no
/// IK, joint-limit, rate-limit or workspace event and the commands follow the shape within
/// 1 µm; otherwise why not.
fn dry_run(
    config: &ValidRobot,
    chain: &Chain,
    q0: &Joints,
    shape: &Shape,
) -> Result<Joints, String> {
    let mut ctrl = Controller::new(config);
    let mut arm = IdealArm::new(*q0);
    let period = config.control_period;
    ctrl.step(0.0, &arm.measured()).unwrap();
    ctrl.set_mode(Mode::Cartesian)
        .map_err(|e| format!("{e:?}"))?;
    let origin = ctrl.cartesian_setpoint().translation.vector;
    ctrl.start_shape(*shape).map_err(|e| format!("{e:?}"))?;
    let end = CYCLES * shape_period(shape);
    let mut finishing = false;
    let mut peak = Joints::zeros(config.dof());
    for k in 1..=(end / period) as usize + 10 {
        let t = k as f64 * period;
        let before = arm.measured();
        let out = ctrl.step(t, &before).unwrap();
        let e = out.events;
        if e.ik_divergence || e.joint_limit || e.rate_limit || e.workspace_limit {
            let what = if e.ik_divergence {
                "IK cannot track"
            } else if e.joint_limit {
                "joint limit"
            } else if e.rate_limit {
                "rate limit"
            } else {
                "workspace"
            };
            // The joint nearest to one of its limits, and how near.
            let (joint, margin) = before
                .iter()
                .zip(chain.min().iter().zip(chain.max()))
                .map(|(q, (lo, hi))| (q - lo).min(hi - q))
                .enumerate()
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .unwrap();
            return Err(format!(
                "{what} at {t:.2} s, J{} {margin:.3} rad from its limit",
                joint + 1
            ));
        }
        arm.step(out.command.as_ref());
        let q = arm.measured();
        for ((p, a), b) in peak.iter_mut().zip(q.iter()).zip(before.iter()) {
            *p = p.max((a - b).abs() / period);
        }
        let p = chain.forward(&q).unwrap().translation.vector;
        let d = (p - ideal(origin, shape, t, end)).norm();
        if d > 1e-6 {
            return Err(format!("off the path by {d:.2e} m at {t:.2} s"));
        }
        if !finishing && t >= end - shape_period(shape) / 4.0 {
            ctrl.finish_shape().unwrap();
            finishing = true;
        }
        if finishing && !ctrl.is_moving() {
            return Ok(peak);
        }
    }
    Err("did not finish".into())
}

/// The ideal shape point at phase `s`, held at the start before the shape begins and after it
/// ends.
fn ideal(origin: Vector3<f64>, shape: &Shape, s: f64, end: f64) -> Vector3<f64> {
    origin + shape.offset(s.clamp(0.0, end))
}

/// What one run in the full control loop gave.
struct Run {
    cmd_mean: f64,
    cmd_max: f64,
    /// Largest commanded speed of each joint (rad/s).
    peak: Joints,
    delay: f64,
    track_mean: f64,
    track_s: f64,
    underflows: u32,
    overruns: u32,
    /// Anything that went wrong (events, faults); empty on a clean run.
    notes: Vec<String>,
    /// The drives' speed limit (rad/s).
    drive_speed: f64,
    /// Where the shape started (m), and its end (phase, s).
    origin: Vector3<f64>,
    end: f64,
    /// FK of each command, at its phase.
    commanded: Vec<(f64, Vector3<f64>)>,
    /// FK of the drives' actual joints, at the time since the start.
    drive_path: Vec<(f64, Vector3<f64>)>,
}

/// The control loop: bus, drive manager and controller, stepped once per period.
/// The simulated drives' actual positions (joint units), in joint order.
fn actual(l: &Rig, config: &ValidRobot) -> Joints {
    let mut q = Joints::zeros(config.dof());
    for (v, joint) in q.iter_mut().zip(config.joints.iter()) {
        *v = l
            .bus()
            .drive(joint.drive.node_id)
            .expect("a drive per joint")
            .joint_position();
    }
    q
}

/// Simulated Whistles with their encoders at `q0` and the given speed limit.
fn virtual_bus(config: &ValidRobot, q0: &Joints, max_speed: f64) -> VirtualBus {
    let drives = config
        .joints
        .iter()
        .zip(q0.iter())
        .filter_map(|(joint, q)| {
            let mut whistle = WhistleConfig::for_joint(joint)?;
            whistle.counts = whistle.units.counts(*q)?;
            whistle.max_speed = max_speed;
            Some(SimWhistle::new(whistle))
        });
    VirtualBus::new(config.drives.can_bitrate, drives)
}

fn run(config: &ValidRobot, chain: &Chain, q0: &Joints, shape: &Shape, drive_speed: f64) -> Run {
    let bus = virtual_bus(config, q0, drive_speed);
    let mut l = Rig::started(config, &DriveSettings::default(), bus);
    l.ctrl_mut().set_mode(Mode::Cartesian).unwrap();
    let origin = l.ctrl().cartesian_setpoint().translation.vector;
    l.ctrl_mut().start_shape(*shape).unwrap();

    let period = config.control_period;
    let end = CYCLES * shape_period(shape);
    let t_start = l.now;
    let mut notes = Vec::new();
    let mut previous = l.manager().measured();
    let (mut cmd_sum, mut cmd_max, mut cmd_n) = (0.0, 0.0f64, 0usize);
    let mut peak = Joints::zeros(config.dof());
    // (time since the start, FK of the drives' actual joints)
    let mut samples = vec![(
        0.0,
        chain
            .forward(&actual(&l, config))
            .unwrap()
            .translation
            .vector,
    )];
    let mut commanded = Vec::new();
    let mut finishing = false;
    let mut k = 0usize;
    while k as f64 * period <= end + 1.0 {
        k += 1;
        let out = l.tick();
        let t = l.now - t_start;
        let e = out.events;
        if e.ik_divergence || e.joint_limit || e.rate_limit || e.workspace_limit {
            notes.push(format!("event at {t:.2} s: {e:?}"));
        }
        if t <= end {
            samples.push((
                t,
                chain
                    .forward(&actual(&l, config))
                    .unwrap()
                    .translation
                    .vector,
            ));
        }
        let command = out.command.expect("Cartesian mode commands every tick");
        // Command k is the shape at phase k · period.
        let phase = k as f64 * period;
        let tool = chain.forward(&command).unwrap().translation.vector;
        let d = (tool - ideal(origin, shape, phase, end)).norm();
        commanded.push((phase, tool));
        cmd_sum += d;
        cmd_max = cmd_max.max(d);
        cmd_n += 1;
        for ((p, a), b) in peak.iter_mut().zip(command.iter()).zip(previous.iter()) {
            *p = p.max((a - b).abs() / period);
        }
        previous = command;
        if !finishing && phase >= end - shape_period(shape) / 4.0 {
            l.ctrl_mut().finish_shape().unwrap();
            finishing = true;
        }
        if finishing && !l.ctrl().is_moving() && t > end {
            break;
        }
    }
    if l.ctrl().is_moving() {
        notes.push("shape still running after 8 cycles".into());
    }
    if !l.manager().is_operational() {
        notes.push(format!("drives not operational: {:?}", l.manager().fault()));
    }
    let stats = l.manager().stats();
    if stats.commands_rejected > 0 {
        notes.push(format!("{} commands rejected", stats.commands_rejected));
    }
    let (delay, track_mean, track_s) = fit_delay(&samples, |s| ideal(origin, shape, s, end));
    Run {
        cmd_mean: cmd_sum / cmd_n as f64,
        cmd_max,
        peak,
        delay,
        track_mean,
        track_s,
        underflows: l.bus().drives().map(|d| d.stats().underflows).sum(),
        overruns: l.bus().drives().map(|d| d.stats().overflows).sum(),
        notes,
        drive_speed,
        origin,
        end,
        commanded,
        drive_path: samples,
    }
}

/// The constant delay τ minimising Σ |p_i − ideal(t_i − τ)|², and the mean and sample standard
/// deviation (spec §8.1) of the distances at that delay.
fn fit_delay(
    samples: &[(f64, Vector3<f64>)],
    ideal: impl Fn(f64) -> Vector3<f64>,
) -> (f64, f64, f64) {
    let cost = |tau: f64| -> f64 {
        samples
            .iter()
            .map(|(t, p)| (*p - ideal(t - tau)).norm_squared())
            .sum()
    };
    let steps = (DELAY_MAX / DELAY_STEP) as usize;
    let (best, _) = (0..=steps)
        .map(|i| {
            let tau = i as f64 * DELAY_STEP;
            (tau, cost(tau))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap();
    // Golden-section search within one grid step either side.
    let (mut a, mut b) = ((best - DELAY_STEP).max(0.0), best + DELAY_STEP);
    let g = (5f64.sqrt() - 1.0) / 2.0;
    for _ in 0..40 {
        let (c, d) = (b - g * (b - a), a + g * (b - a));
        if cost(c) < cost(d) {
            b = d;
        } else {
            a = c;
        }
    }
    let tau = 0.5 * (a + b);
    let d: Vec<f64> = samples
        .iter()
        .map(|(t, p)| (*p - ideal(t - tau)).norm())
        .collect();
    let n = d.len() as f64;
    let mean = d.iter().sum::<f64>() / n;
    let s = (d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    (tau, mean, s)
}
