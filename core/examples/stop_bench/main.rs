//! How every shipped robot comes to rest: each motion at cruise, stopped by each cause.
//!
//! `cargo run --release -p armgate-core --example stop_bench`
//!
//! For every robot file in `robots/` × {joint move, Cartesian line, diagonal Cartesian line,
//! blended sequence, twist stream, joint-velocity stream} × {ST, CM, OF, workspace boundary,
//! stream timeout, IK divergence, following error}, an ideal arm follows the commands; from the
//! stop's cause on,
//! per tick of commanded joints: the peak acceleration over `max_acceleration` (the worst
//! joint), the peak jerk over `max_jerk` (where the robot file sets one), per tick of Cartesian
//! set-points (Cartesian motions that stop along their path): the peak change of an axis's
//! velocity over that axis's Cartesian `max_acceleration` (the worst of x, y, z, rx, ry, rz;
//! "-" without set-points), the time and tool distance to rest, and the tool's largest
//! distance from the path (Cartesian lines and twist stream: the straight line). The diagonal
//! line goes along (1, −1, ½) (issue 33's (0.10, −0.10, 0.05) m on ranger-mk1), just long
//! enough to reach cruise, so that a stop at its middle runs into the line's own deceleration
//! phase. "refused":
//! the motion was refused up front (boundary case); "entered box": the tool was strictly inside
//! the box put across its way on some tick.
//!
//! IK divergence (`WN22`, Cartesian line only): the up-front line check is turned off
//! (`ik.check_lines = false`) and the line runs from the start along the first of ±x, ±z, ±y,
//! as long as the workspace bounds allow (up to 1 m), on which the tick loses its IK solution;
//! figures from the tick that raised it, whose speed is in the note ("at N mm/s": the tick may
//! have slowed the line down before it gave up).
//!
//! Following error (cause 9): at the same point as `ST`, the arm is held where it is (a blocked
//! drive; streams keep sending) until the controller finds a joint too far behind its command
//! and stops; figures from that tick, with the joint and its lag in the note.
//!
//! The whole arm (issue 35): every commanded pose of every run, motion and braking (and the
//! probes that find a line's direction), is measured by [`BodyOracle`]: every link capsule
//! against the exclusion boxes and the other links it is checked against, the tool's against
//! the bounds. "clear mm" is the least gap over the run's ticks and to what (`L3/B1`: link 3
//! to box 1, `L5/L2`: to link 2, `L6/out`: the bounds' faces); after the table, the least per
//! robot. A link that comes into contact it was not in at the tick before (gap ≤ 0) is named
//! in the note (`entered L3 hits B1`) and on stderr, and the bench exits non-zero.
#![allow(missing_docs, clippy::unwrap_used, clippy::indexing_slicing)]

mod figures;

use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use armgate_core::config::{ValidRobot, load_file};
use armgate_core::kinematics::Joints;
use armgate_core::math::{Frame, Twist, Vector3};
use armgate_core::motion::{Controller, Mode, StopCause};
use armgate_core::sim::{BodyOracle, Entry, IdealArm};
use armgate_protocol::client::TwistFrame;
use figures::{Figures, between, measure, refused};

#[derive(Clone, Copy, PartialEq, Debug)]
enum Motion {
    JointMove,
    Line,
    Diagonal,
    Blended,
    Twist,
    JointRates,
}

#[derive(Clone, Copy, PartialEq, Debug)]
enum Cause {
    St,
    Cm,
    Of,
    Boundary,
    Timeout,
    Wn22,
    FollowingError,
}

const MOTIONS: [Motion; 6] = [
    Motion::JointMove,
    Motion::Line,
    Motion::Diagonal,
    Motion::Blended,
    Motion::Twist,
    Motion::JointRates,
];
const CAUSES: [Cause; 7] = [
    Cause::St,
    Cause::Cm,
    Cause::Of,
    Cause::Boundary,
    Cause::Timeout,
    Cause::Wn22,
    Cause::FollowingError,
];
/// Ticks after the cause at most (rest is normally reached much earlier).
const MAX_TICKS: usize = 20_000;
/// Contacts entered over every run (probes included): any makes the bench fail.
static ENTRIES: AtomicUsize = AtomicUsize::new(0);
/// The case under way, for the stderr line of a contact entered.
static CASE: Mutex<String> = Mutex::new(String::new());

struct Run {
    config: ValidRobot,
    ctrl: Controller,
    arm: IdealArm,
    now: f64,
    /// Commanded joints, one per tick.
    commands: Vec<Joints>,
    /// The Cartesian set-point of each tick (none while the motion is not Cartesian).
    setpoints: Vec<Option<Frame>>,
    /// The index in `commands` of the first tick that raised `WN22`.
    ik_divergence: Option<usize>,
    /// The arm is held where it is (a blocked drive): it takes no commands.
    held: bool,
    /// The index in `commands` of the first tick that raised `ER43`, with its text's joint
    /// and lag.
    following_error: Option<(usize, String)>,
    /// Every commanded pose, measured against the boxes, the bounds and the other links.
    body: BodyOracle,
    /// The first contact a commanded pose entered.
    entered: Option<Entry>,
}

impl Run {
    fn new(config: &ValidRobot, q0: &Joints) -> Self {
        let mut run = Self {
            config: config.clone(),
            ctrl: Controller::new(config),
            arm: IdealArm::new(*q0),
            now: 0.0,
            commands: Vec::new(),
            setpoints: Vec::new(),
            ik_divergence: None,
            held: false,
            following_error: None,
            body: BodyOracle::new(config, q0),
            entered: None,
        };
        run.tick();
        run
    }

    fn tick(&mut self) {
        self.now += self.config.control_period;
        let out = self.ctrl.step(self.now, &self.arm.measured()).unwrap();
        if !self.held {
            self.arm.step(out.command.as_ref());
        }
        let q = out.command.unwrap_or(self.arm.measured());
        self.commands.push(q);
        if let Err(entry) = self.body.check(&q) {
            ENTRIES.fetch_add(1, Ordering::Relaxed);
            eprintln!(
                "{}: t {:.3} s: {} entered (gap {:.5} m) at q {:?}, {:?}, collision event {:?}",
                CASE.lock().unwrap(),
                self.now,
                entry.hit,
                entry.gap,
                &q[..],
                self.ctrl.motion(),
                out.events.collision,
            );
            self.entered.get_or_insert(entry);
        }
        self.setpoints.push(out.setpoint);
        if out.events.ik_divergence && self.ik_divergence.is_none() {
            self.ik_divergence = Some(self.commands.len() - 1);
        }
        if let (Some(lag), None) = (out.events.following_error, &self.following_error) {
            let note = format!(
                "j{} {:.3} behind",
                lag.joint,
                f64::from(lag.error_milli) / 1e3
            );
            self.following_error = Some((self.commands.len() - 1, note));
        }
    }

    /// The figures from tick `from` on, or for a following error from the tick that found it.
    fn measure(
        &self,
        from: usize,
        line: Option<(Vector3<f64>, Vector3<f64>)>,
        boxed: Option<[f64; 6]>,
    ) -> Figures {
        if !self.held {
            return measure(self, from, line, boxed);
        }
        let Some((from, note)) = &self.following_error else {
            return Figures {
                note: "no following error".to_string(),
                clearance: self.body.nearest(),
                ..refused()
            };
        };
        let mut f = measure(self, *from, line, boxed);
        f.note.clone_from(note);
        f
    }

    fn pose(&self, q: &Joints) -> Vector3<f64> {
        self.ctrl.chain().forward(q).unwrap().translation.vector
    }
}

/// A comfortable start: mid-range, nudged, with the tool inside the workspace.
fn start_pose(config: &ValidRobot) -> Joints {
    let ctrl = Controller::new(config);
    let chain = ctrl.chain();
    let mut q = chain.mid_range();
    let (min, max) = (chain.min().to_vec(), chain.max().to_vec());
    for (i, v) in q.iter_mut().enumerate() {
        *v += 0.12 * (max[i] - min[i]).min(2.0) * if i % 2 == 0 { 0.5 } else { -0.5 };
    }
    q
}

/// A straight Cartesian line from the start that the controller accepts: the first of ±x, ±y,
/// ±z, of a length that reaches cruise.
fn line_goal(run: &mut Run, length: f64) -> Option<(Frame, Vector3<f64>)> {
    let ways = [
        Vector3::x(),
        -Vector3::x(),
        Vector3::z(),
        -Vector3::z(),
        Vector3::y(),
        -Vector3::y(),
    ];
    first_accepted(run, &ways, &[length, 0.5 * length, 0.25 * length])
}

/// The first line along one of `ways` (in order), each tried at `lengths` (in order), that the
/// line check accepts from the set-point: its goal and unit direction. The accepted probe is
/// stopped, settled and forgotten, so the caller starts the measured run afresh.
fn first_accepted(
    run: &mut Run,
    ways: &[Vector3<f64>],
    lengths: &[f64],
) -> Option<(Frame, Vector3<f64>)> {
    let start = run.ctrl.cartesian_setpoint();
    for way in ways {
        for length in lengths {
            let mut goal = start;
            goal.translation.vector += way * *length;
            if run.ctrl.move_cartesian(goal, 0.0).is_ok() {
                stop_now(run, Cause::St);
                settle(run);
                run.commands.clear();
                run.setpoints.clear();
                return Some((goal, way.normalize()));
            }
        }
    }
    None
}

/// A line along (1, −1, ½) or its reverse, just long enough to reach cruise on x: a stop at its
/// middle runs into the line's own deceleration phase.
fn diagonal_goal(run: &mut Run) -> Option<(Frame, Vector3<f64>)> {
    let c = &run.config.config().cartesian;
    let x = (1.11 * c.max_velocity[0] * c.max_velocity[0] / c.max_acceleration[0]).clamp(0.02, 0.2);
    let ways = [Vector3::new(1.0, -1.0, 0.5), Vector3::new(-1.0, 1.0, -0.5)];
    first_accepted(run, &ways, &[x, 0.5 * x])
}

fn settle(run: &mut Run) {
    for _ in 0..MAX_TICKS {
        run.tick();
        if !run.ctrl.is_moving() {
            break;
        }
    }
}

fn stop_now(run: &mut Run, cause: Cause) {
    match cause {
        Cause::St => run.ctrl.stop(StopCause::Stop),
        Cause::Cm => {
            let other = if run.ctrl.mode() == Mode::Joint {
                Mode::Cartesian
            } else {
                Mode::Joint
            };
            run.ctrl.set_mode(other).unwrap();
        }
        Cause::Of => run.ctrl.stop(StopCause::PowerOff),
        Cause::FollowingError => run.held = true,
        Cause::Boundary | Cause::Timeout | Cause::Wn22 => {}
    }
}

/// The cruise length of a Cartesian line along one axis: twice the distance to reach cruise.
fn cruise_length(config: &ValidRobot) -> f64 {
    let c = &config.config().cartesian;
    (3.0 * c.max_velocity[0] * c.max_velocity[0] / c.max_acceleration[0]).clamp(0.06, 0.3)
}

/// A planned motion run to its end: whether the tool entered the box across its way.
fn run_through(run: &mut Run, config: &ValidRobot) -> Figures {
    settle(run);
    measure(
        run,
        0,
        None,
        config.config().workspace.boxes.first().copied(),
    )
}

/// A box 2 cm deep across the way ahead of `p`, in direction `dir`, `ahead` metres away.
fn box_ahead(p: &Vector3<f64>, dir: &Vector3<f64>, ahead: f64) -> [f64; 6] {
    let c = p + dir * (ahead + 0.01);
    let half = |i: usize| if dir[i].abs() > 0.5 { 0.01 } else { 0.2 };
    [
        c.x - half(0),
        c.x + half(0),
        c.y - half(1),
        c.y + half(1),
        c.z - half(2),
        c.z + half(2),
    ]
}

/// The robot with `bx` for its only box; where the arm's body meets it at home (the robot
/// file's check refuses it) or at `start`, the box narrowed across the way to a half and a
/// quarter; none if those meet it too.
fn with_box(config: &ValidRobot, bx: [f64; 6], start: &Joints) -> Option<ValidRobot> {
    [1.0, 0.5, 0.25].into_iter().find_map(|scale| {
        let mut narrowed = bx;
        for axis in 0..3 {
            let (lo, hi) = (bx[2 * axis], bx[2 * axis + 1]);
            // Only the sides across the way (40 cm), not its 2 cm depth.
            if hi - lo > 0.1 {
                let (mid, half) = (0.5 * (lo + hi), 0.5 * (hi - lo) * scale);
                narrowed[2 * axis] = mid - half;
                narrowed[2 * axis + 1] = mid + half;
            }
        }
        config
            .clone()
            .edit(|c| {
                c.workspace.boxes.clear();
                c.workspace.boxes.push(narrowed).unwrap();
            })
            .ok()
            .filter(|boxed| {
                let mut body = BodyOracle::new(boxed, start);
                let _ = body.check(start);
                body.nearest().is_none_or(|(gap, _)| gap > 0.0)
            })
    })
}

/// The figures of a boundary case whose box the arm's body meets at home or at the start,
/// however narrow.
fn box_meets_arm() -> Figures {
    Figures {
        note: "box meets the arm".to_string(),
        ..refused()
    }
}

fn run_case(config: &ValidRobot, motion: Motion, cause: Cause) -> Option<Figures> {
    let q0 = start_pose(config);
    let dt = config.control_period;
    if cause == Cause::Timeout && !matches!(motion, Motion::Twist | Motion::JointRates) {
        return None;
    }
    if cause == Cause::Wn22 {
        return (motion == Motion::Line)
            .then(|| diverging_line(config, &q0))
            .flatten();
    }
    let probe = Run::new(config, &q0);
    let p0 = probe.pose(&q0);
    match motion {
        Motion::JointMove => {
            let chain = probe.ctrl.chain();
            let mut goal = q0;
            for (i, g) in goal.iter_mut().enumerate() {
                let room = if i % 2 == 0 {
                    chain.max()[i] - *g
                } else {
                    *g - chain.min()[i]
                };
                *g += if i % 2 == 0 { 1.0 } else { -1.0 } * (0.5 * room).min(0.6);
            }
            let config = if cause == Cause::Boundary {
                let p1 = probe.pose(&goal);
                let dir = (p1 - p0).normalize();
                // Across the tool's way, 3/4 of the straight distance ahead.
                let bx = box_ahead(&p0, &dir, 0.75 * (p1 - p0).norm() - 0.01);
                let Some(config) = with_box(config, bx, &q0) else {
                    return Some(box_meets_arm());
                };
                config
            } else {
                config.clone()
            };
            let mut run = Run::new(&config, &q0);
            run.ctrl.set_mode(Mode::Joint).unwrap();
            let Ok(duration) = run.ctrl.move_joints(&goal, 0.0) else {
                return Some(refused());
            };
            if cause == Cause::Boundary {
                return Some(run_through(&mut run, &config));
            }
            let ticks = (0.5 * duration / dt) as usize;
            for _ in 0..ticks {
                run.tick();
            }
            let from = run.commands.len();
            stop_now(&mut run, cause);
            settle(&mut run);
            Some(run.measure(from, None, None))
        }
        Motion::Line | Motion::Diagonal | Motion::Blended => {
            let length = cruise_length(config);
            let mut run = Run::new(config, &q0);
            run.ctrl.set_mode(Mode::Cartesian).unwrap();
            let (goal, dir) = if motion == Motion::Diagonal {
                diagonal_goal(&mut run)?
            } else {
                line_goal(&mut run, length)?
            };
            let origin = run.ctrl.cartesian_setpoint().translation.vector;
            let q_start = *run.commands.last().unwrap_or(&q0);
            let config = if cause == Cause::Boundary {
                let ahead = 0.75 * (goal.translation.vector - origin).norm();
                let Some(config) = with_box(config, box_ahead(&origin, &dir, ahead), &q_start)
                else {
                    return Some(box_meets_arm());
                };
                config
            } else {
                config.clone()
            };
            let mut run = Run::new(&config, &q_start);
            run.ctrl.set_mode(Mode::Cartesian).unwrap();
            let c = &config.config().cartesian;
            let v = c.max_velocity[0]
                .min(c.max_velocity[1])
                .min(c.max_velocity[2]);
            let a = c.max_acceleration[0]
                .min(c.max_acceleration[1])
                .min(c.max_acceleration[2]);
            let leg = (goal.translation.vector - origin).norm();
            let duration = if motion != Motion::Blended {
                match run.ctrl.move_cartesian(goal, 0.0) {
                    Ok(d) => d,
                    Err(_) => return Some(refused()),
                }
            } else {
                // Two legs with a corner blended within 1 cm: along the line, then sideways.
                let side = if dir.z.abs() > 0.5 {
                    Vector3::x()
                } else {
                    Vector3::z()
                };
                let mut corner = goal;
                corner.translation.vector = origin + dir * leg;
                let mut end = corner;
                end.translation.vector += side * 0.5 * leg;
                run.ctrl.set_cartesian_via(0, corner, 0.0).ok()?;
                run.ctrl.set_cartesian_via(1, end, 0.0).ok()?;
                run.ctrl.set_cartesian_blend(0, Some(0.01)).unwrap();
                if run.ctrl.start_cartesian_sequence().is_err() {
                    return Some(refused());
                }
                // The stop comes in the blend, near the corner.
                2.0 * (leg / v + v / a)
            };
            if cause == Cause::Boundary {
                return Some(run_through(&mut run, &config));
            }
            for _ in 0..(0.5 * duration / dt) as usize {
                run.tick();
            }
            let from = run.commands.len();
            stop_now(&mut run, cause);
            settle(&mut run);
            let line = (motion != Motion::Blended).then_some((origin, dir));
            Some(run.measure(from, line, None))
        }
        Motion::Twist | Motion::JointRates => {
            let mut run = Run::new(config, &q0);
            let c = &config.config().cartesian;
            let (mode, dir) = if motion == Motion::Twist {
                run.ctrl.set_mode(Mode::Cartesian).unwrap();
                let (_, dir) = line_goal(&mut run, cruise_length(config))?;
                (Mode::Cartesian, dir)
            } else {
                (Mode::Joint, Vector3::x())
            };
            let chain = run.ctrl.chain().clone();
            let q_start = *run.commands.last().unwrap_or(&q0);
            let speed = 0.8
                * c.max_velocity[0]
                    .min(c.max_velocity[1])
                    .min(c.max_velocity[2]);
            let rates: Joints = {
                let mut r = q_start;
                for (i, v) in r.iter_mut().enumerate() {
                    let j = &config.config().joints[i];
                    let up = chain.max()[i] - q_start[i] > q_start[i] - chain.min()[i];
                    *v = 0.8 * j.max_velocity.min(j.max_rate) * if up { 1.0 } else { -1.0 };
                }
                r
            };
            // Cruise for 2 s or the time to reach it, whichever is longer.
            let accel_time = config
                .config()
                .joints
                .iter()
                .map(|j| j.max_velocity.min(j.max_rate) / j.max_acceleration)
                .fold(speed / c.max_acceleration[0], f64::max);
            let cruise_ticks = ((accel_time + 1.0) / dt) as usize;
            let config = if cause == Cause::Boundary {
                // Ahead of the tool where it will be at the end of the cruise, plus 2 cm.
                let mut probe = Run::new(config, &q_start);
                probe.ctrl.set_mode(mode).unwrap();
                for _ in 0..cruise_ticks {
                    send(&mut probe, motion, speed, &dir, &rates);
                    probe.tick();
                }
                let p1 = probe.pose(probe.commands.last().unwrap());
                let p_start = probe.pose(&q_start);
                let way = (p1 - p_start).normalize();
                let Some(config) = with_box(config, box_ahead(&p1, &way, 0.02), &q_start) else {
                    return Some(box_meets_arm());
                };
                config
            } else {
                config.clone()
            };
            let mut run = Run::new(&config, &q_start);
            run.ctrl.set_mode(mode).unwrap();
            let origin = run.pose(&q_start);
            for _ in 0..cruise_ticks {
                send(&mut run, motion, speed, &dir, &rates);
                run.tick();
            }
            let from = run.commands.len();
            if cause == Cause::Boundary {
                for _ in 0..MAX_TICKS / 4 {
                    send(&mut run, motion, speed, &dir, &rates);
                    run.tick();
                }
                run.ctrl.stop(StopCause::Stop);
                settle(&mut run);
                let boxed = config.config().workspace.boxes.first().copied();
                let line = (motion == Motion::Twist).then_some((origin, dir));
                return Some(measure(&run, from, line, boxed));
            }
            stop_now(&mut run, cause);
            // A held arm: the stream goes on until the controller finds the lag.
            for _ in 0..MAX_TICKS / 4 {
                if !run.held || run.following_error.is_some() {
                    break;
                }
                send(&mut run, motion, speed, &dir, &rates);
                run.tick();
            }
            settle(&mut run);
            let line = (motion == Motion::Twist).then_some((origin, dir));
            Some(run.measure(from, line, None))
        }
    }
}

/// The stop that `WN22` begins on an unchecked Cartesian line the tick cannot follow to its end.
fn diverging_line(config: &ValidRobot, q0: &Joints) -> Option<Figures> {
    let unchecked = config.clone().edit(|c| c.ik.check_lines = false).unwrap();
    for (name, dir) in [
        ("+x", Vector3::x()),
        ("-x", -Vector3::x()),
        ("+z", Vector3::z()),
        ("-z", -Vector3::z()),
        ("+y", Vector3::y()),
        ("-y", -Vector3::y()),
    ] {
        for length in [1.0, 0.6, 0.4, 0.25] {
            let mut run = Run::new(&unchecked, q0);
            run.ctrl.set_mode(Mode::Cartesian).unwrap();
            let mut goal = run.ctrl.cartesian_setpoint();
            let origin = goal.translation.vector;
            goal.translation.vector += dir * length;
            if run.ctrl.move_cartesian(goal, 0.0).is_err() {
                continue;
            }
            settle(&mut run);
            let Some(from) = run.ik_divergence.filter(|k| *k >= 2) else {
                continue;
            };
            let mut f = measure(&run, from, Some((origin, dir)), None);
            let dt = unchecked.control_period;
            let c = &run.commands;
            let speed = (run.pose(&c[from - 1]) - run.pose(&c[from - 2])).norm() / dt;
            f.note = format!("at {:.0} mm/s, {length} m along {name}", speed * 1e3);
            return Some(f);
        }
    }
    None
}

fn send(run: &mut Run, motion: Motion, speed: f64, dir: &Vector3<f64>, rates: &Joints) {
    if motion == Motion::Twist {
        let v = dir * speed;
        let twist = Twist::new(v.x, v.y, v.z, 0.0, 0.0, 0.0);
        let _ = run.ctrl.stream_twist(twist, TwistFrame::Base);
    } else {
        let _ = run.ctrl.stream_joint_rates(rates);
    }
}

fn main() {
    let dir = format!("{}/../robots", env!("CARGO_MANIFEST_DIR"));
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    println!(
        "| robot | motion | cause | accel/max | jerk/max | cart acc/max | stop s | dist mm | dev mm | clear mm | note |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    let (mut worst, mut worst_cartesian) = (0.0f64, 0.0f64);
    // Per robot: the least clearance, to what, in which case.
    let mut least: Vec<(String, f64, String)> = Vec::new();
    for path in files {
        let config = load_file(&path).unwrap();
        let name = config.config().name.clone();
        let mut robot_least: Option<(f64, String)> = None;
        for motion in MOTIONS {
            for cause in CAUSES {
                *CASE.lock().unwrap() = format!("{name} {motion:?} {cause:?}");
                let Some(f) = run_case(&config, motion, cause) else {
                    continue;
                };
                worst = worst.max(f.accel);
                let path = matches!(motion, Motion::Line | Motion::Diagonal | Motion::Blended);
                if path && cause != Cause::Cm {
                    worst_cartesian = worst_cartesian.max(f.cartesian.unwrap_or(0.0));
                }
                let opt = |v: Option<f64>, scale: f64| {
                    v.map_or("-".to_string(), |v| format!("{:.3}", v * scale))
                };
                let clear = f.clearance.map_or("-".to_string(), |(gap, hit)| {
                    format!("{:.2} {}", gap * 1e3, between(&hit))
                });
                if let Some((gap, hit)) = f.clearance
                    && robot_least.as_ref().is_none_or(|(g, _)| gap < *g)
                {
                    robot_least = Some((gap, format!("{}, {motion:?} {cause:?}", between(&hit))));
                }
                println!(
                    "| {name} | {motion:?} | {cause:?} | {:.2} | {} | {} | {:.2} | {:.1} | {} | {clear} | {} |",
                    f.accel,
                    opt(f.jerk, 1.0),
                    opt(f.cartesian, 1.0),
                    f.time,
                    f.distance * 1e3,
                    opt(f.deviation, 1e3),
                    f.note,
                );
            }
        }
        if let Some((gap, what)) = robot_least {
            least.push((name.to_string(), gap, what));
        }
    }
    println!("\nworst accel/max over every case: {worst:.2}");
    println!(
        "worst Cartesian axis acc/max of a stop along a Cartesian path (ST, OF, boundary, following error): {worst_cartesian:.2}"
    );
    let list: Vec<String> = least
        .iter()
        .map(|(name, gap, what)| format!("{name} {:.2} ({what})", gap * 1e3))
        .collect();
    println!(
        "least clearance of any link over every tick of every case (mm): {}",
        list.join("; ")
    );
    let entries = ENTRIES.load(Ordering::Relaxed);
    println!("links that entered a box, the bounds or another link: {entries}");
    if entries > 0 {
        std::process::exit(1);
    }
}
