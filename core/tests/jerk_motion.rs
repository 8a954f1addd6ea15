//! Jerk-limited moves through the whole controller (robots/ranger-mk1-jerk.toml): joint and
//! Cartesian moves arrive exactly and their commanded set-points stay within the velocity,
//! acceleration and jerk limits, which the seed's trapezoids (robots/ranger-mk1.toml) do not.
#![allow(
    clippy::approx_constant,
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod common;

use armgate_core::config::{JointConfig, ValidRobot};
use armgate_core::kinematics::Joints;
use armgate_core::math::{self, Frame, Rotation3, Vector3};
use armgate_core::motion::{Controller, JointGenerator, Mode, StepOutput, StopCause};
use armgate_core::rng::SplitMix64;
use armgate_core::sim::IdealArm;

/// A comfortable ranger-mk1 pose in front of the base, away from limits and singularities.
const MK1_READY: [f64; 6] = [1.5708, 0.6, -0.4, 0.2, 1.8, 0.1];

/// Runs `start` on a controller with an ideal arm from `MK1_READY` in `mode` and returns every
/// tick's output until the motion finished.
fn run(
    config: &ValidRobot,
    mode: Mode,
    start: impl FnOnce(&mut Controller, Frame),
) -> Vec<StepOutput> {
    let mut ctrl = Controller::new(config);
    let mut arm = IdealArm::new(Joints::from_slice(&MK1_READY).unwrap());
    let period = config.control_period;
    let mut now = 0.0;
    let mut tick = |ctrl: &mut Controller, arm: &mut IdealArm| {
        now += period;
        let out = ctrl.step(now, &arm.measured()).unwrap();
        arm.step(out.command.as_ref());
        out
    };
    tick(&mut ctrl, &mut arm);
    ctrl.set_mode(mode).unwrap();
    let first = tick(&mut ctrl, &mut arm);
    start(&mut ctrl, first.measured_pose);
    let mut outs = vec![first];
    for _ in 0..5000 {
        let out = tick(&mut ctrl, &mut arm);
        outs.push(out);
        if out.events.motion_finished {
            return outs;
        }
    }
    panic!("the move never finished");
}

/// The largest |first, second, third difference| of a sampled signal divided by dt, dt², dt³.
/// Each is a weighted mean of the velocity, acceleration or jerk over the samples' span (a
/// B-spline kernel of unit weight), so none can exceed the largest value of its derivative.
fn difference_peaks(x: &[f64], dt: f64) -> [f64; 3] {
    let d1: Vec<f64> = x.windows(2).map(|w| w[1] - w[0]).collect();
    let d2: Vec<f64> = d1.windows(2).map(|w| w[1] - w[0]).collect();
    let d3: Vec<f64> = d2.windows(2).map(|w| w[1] - w[0]).collect();
    let peak = |d: &[f64], scale: f64| d.iter().fold(0.0f64, |m, v| m.max(v.abs())) / scale;
    [peak(&d1, dt), peak(&d2, dt * dt), peak(&d3, dt * dt * dt)]
}

/// Within `limit` up to 1e-9 relative, plus the rounding of a set-point (1e-15 of its size
/// divided by dt³ for a third difference).
fn within(value: f64, limit: f64, rounding: f64) -> bool {
    value <= limit * (1.0 + 1e-9) + rounding
}

/// Asserts that joint `i`'s commands `q` (one a tick of `dt`) keep `v_max` and the joint's
/// acceleration and jerk limits.
fn assert_within_limits(joint: &JointConfig, i: usize, q: &[f64], v_max: f64, dt: f64) {
    let rounding = 8.0 * f64::EPSILON * 5.0 / (dt * dt * dt);
    let [v, a, j] = difference_peaks(q, dt);
    assert!(within(v, v_max, 0.0), "joint {i}: v {v}");
    assert!(within(a, joint.max_acceleration, 0.0), "joint {i}: a {a}");
    assert!(
        within(j, joint.max_jerk.unwrap(), rounding),
        "joint {i}: j {j}"
    );
}

#[test]
fn jerk_limited_joint_move_arrives_synchronised_within_every_limit() {
    let config = common::robot("ranger-mk1-jerk");
    let goal = [1.2, 0.9, -0.1, -0.3, 1.5, 0.6];
    let outs = run(&config, Mode::Joint, |ctrl, _| {
        ctrl.move_joints(&goal, 0.0).unwrap();
    });
    let commands: Vec<Joints> = outs.iter().map(|o| o.command.unwrap()).collect();
    assert_eq!(commands.last().unwrap()[..], goal[..]);
    let dt = config.control_period;
    for (i, joint) in config.joints.iter().enumerate() {
        let q: Vec<f64> = commands.iter().map(|c| c[i]).collect();
        assert_within_limits(joint, i, &q, joint.max_velocity, dt);
        // Synchronised: every joint has covered the same fraction of its way at every tick.
        let fraction = |k: usize| (q[k] - MK1_READY[i]) / (goal[i] - MK1_READY[i]);
        let fraction0 = |k: usize| (commands[k][0] - MK1_READY[0]) / (goal[0] - MK1_READY[0]);
        assert!((0..q.len()).all(|k| (fraction(k) - fraction0(k)).abs() < 1e-12));
    }
    assert!(
        outs.iter()
            .all(|o| !o.events.rate_limit && !o.events.joint_limit)
    );

    // The seed's trapezoid on the same move steps its acceleration: far more than the jerk
    // limit at this period.
    let seed = common::robot("ranger-mk1");
    let outs = run(&seed, Mode::Joint, |ctrl, _| {
        ctrl.move_joints(&goal, 0.0).unwrap();
    });
    let q: Vec<f64> = outs.iter().map(|o| o.command.unwrap()[0]).collect();
    let [_, _, j] = difference_peaks(&q, dt);
    assert!(
        j > 2.0 * config.joints[0].max_jerk.unwrap(),
        "trapezoid jerk {j}"
    );
}

/// A mode change while a joint move accelerates stops the arm in joint space; the stop first
/// ramps the acceleration out, so no tick steps it (the brake alone starts from none: 1.35 ×
/// `max_jerk` in stop_bench's blend).
#[test]
fn a_stop_that_begins_while_accelerating_keeps_the_jerk_limits() {
    let config = common::robot("ranger-mk1-jerk");
    let dt = config.control_period;
    let goal = [1.2, 0.9, -0.1, -0.3, 1.5, 0.6];
    for after in [2, 4, 8, 15, 30] {
        let mut ctrl = Controller::new(&config);
        let mut arm = IdealArm::new(Joints::from_slice(&MK1_READY).unwrap());
        let mut now = 0.0;
        let mut commands = Vec::new();
        let mut tick = |ctrl: &mut Controller, arm: &mut IdealArm| {
            now += dt;
            let out = ctrl.step(now, &arm.measured()).unwrap();
            arm.step(out.command.as_ref());
            commands.extend(out.command);
        };
        tick(&mut ctrl, &mut arm);
        ctrl.set_mode(Mode::Joint).unwrap();
        tick(&mut ctrl, &mut arm);
        ctrl.move_joints(&goal, 0.0).unwrap();
        for _ in 0..after {
            tick(&mut ctrl, &mut arm);
        }
        ctrl.set_mode(Mode::Cartesian).unwrap();
        for _ in 0..2000 {
            tick(&mut ctrl, &mut arm);
            if !ctrl.is_moving() {
                break;
            }
        }
        assert!(!ctrl.is_moving(), "after {after}: still moving");
        let rounding = 8.0 * f64::EPSILON * 5.0 / (dt * dt * dt);
        for (i, joint) in config.joints.iter().enumerate() {
            let q: Vec<f64> = commands.iter().map(|c| c[i]).collect();
            let [_, a, j] = difference_peaks(&q, dt);
            assert!(
                within(a, joint.max_acceleration, 0.0),
                "after {after}: joint {i}: a {a}"
            );
            assert!(
                within(j, joint.max_jerk.unwrap(), rounding),
                "after {after}: joint {i}: j {j}"
            );
        }
    }
}

/// The stop that `WN22` begins (a Cartesian line the tick cannot follow to its end, the
/// up-front check turned off so that the tick meets it) keeps the acceleration and jerk limits
/// and ends as a rate-limited joint-space stop does: from at most 0.2 rad/s at 0.5 rad/s²
/// (0.4 s) plus a 0.1 s jerk ramp at each end, 0.6 s (31 ticks).
#[test]
fn the_stop_that_wn22_begins_keeps_the_jerk_limits() {
    let config = common::robot("ranger-mk1-jerk")
        .edit(|c| c.ik.check_lines = false)
        .unwrap();
    let dt = config.control_period;
    let mut ctrl = Controller::new(&config);
    let mut arm = IdealArm::new(Joints::from_slice(&MK1_READY).unwrap());
    let mut now = 0.0;
    let mut commands = Vec::new();
    let mut diverged_at = None;
    ctrl.step(now, &arm.measured()).unwrap();
    ctrl.set_mode(Mode::Cartesian).unwrap();
    let mut goal = ctrl.cartesian_setpoint();
    goal.translation.vector.x += 1.0;
    ctrl.move_cartesian(goal, 0.0).unwrap();
    for tick in 0..20_000 {
        now += dt;
        let out = ctrl.step(now, &arm.measured()).unwrap();
        arm.step(out.command.as_ref());
        commands.extend(out.command);
        if out.events.ik_divergence && diverged_at.is_none() {
            diverged_at = Some(tick);
        }
        if !ctrl.is_moving() {
            break;
        }
    }
    let diverged_at = diverged_at.expect("the line is lost on the way");
    assert_eq!(ctrl.stop_cause().0, Some(StopCause::IkDivergence));
    assert!(!ctrl.is_moving());
    let stop_ticks = commands.len() - diverged_at;
    assert!(stop_ticks <= 31, "at rest {stop_ticks} ticks after WN22");
    for (i, joint) in config.joints.iter().enumerate() {
        let q: Vec<f64> = commands.iter().map(|c| c[i]).collect();
        assert_within_limits(joint, i, &q, joint.max_rate, dt);
    }
}

#[test]
fn jerk_limited_cartesian_move_arrives_within_every_axis_limit() {
    let config = common::robot("ranger-mk1-jerk");
    let mut goal = Frame::identity();
    let mut start = Frame::identity();
    let outs = run(&config, Mode::Cartesian, |ctrl, pose| {
        start = pose;
        goal = Frame::from_parts(
            (pose.translation.vector + Vector3::new(0.03, -0.05, 0.04)).into(),
            Rotation3::from_axis_angle(&Vector3::z_axis(), 0.1) * pose.rotation,
        );
        ctrl.move_cartesian(goal, 0.0).unwrap();
    });
    assert!(
        outs.iter()
            .all(|o| !o.events.ik_divergence && !o.events.rate_limit)
    );
    let setpoints: Vec<Frame> = outs.iter().filter_map(|o| o.setpoint).collect();
    assert_eq!(*setpoints.last().unwrap(), goal);
    // The commanded pose reached through the IK.
    let last = outs.last().unwrap().command.unwrap();
    let reached = math::diff(&config_pose(&config, &last), &goal);
    assert!(reached.norm() < 1e-9, "{reached:?}");
    let dt = config.control_period;
    let limits = &config.cartesian;
    let axes = limits
        .max_velocity
        .iter()
        .zip(&limits.max_acceleration)
        .zip(limits.max_jerk.unwrap());
    let rounding = 8.0 * f64::EPSILON * 2.0 / (dt * dt * dt);
    for (axis, ((v_max, a_max), j_max)) in axes.enumerate() {
        // Offsets from the start (x, y, z, then the rotation vector turned so far).
        let x: Vec<f64> = setpoints
            .iter()
            .map(|sp| math::diff(&start, sp)[axis])
            .collect();
        let [v, a, j] = difference_peaks(&x, dt);
        assert!(within(v, *v_max, 0.0), "axis {axis}: v {v}");
        assert!(within(a, *a_max, 1e-12), "axis {axis}: a {a}");
        assert!(within(j, j_max, rounding), "axis {axis}: j {j}");
    }
}

#[test]
fn random_jerk_limited_joint_moves_stay_within_every_limit() {
    let mut rng = SplitMix64::new(13);
    let dt = 0.01;
    for _ in 0..200 {
        let draw = |rng: &mut SplitMix64, lo: f64, hi: f64| {
            Joints::from_slice(&[0; 3].map(|_| rng.log_uniform(lo, hi))).unwrap()
        };
        let (v, a, j) = (
            draw(&mut rng, 0.1, 2.0),
            draw(&mut rng, 0.1, 5.0),
            draw(&mut rng, 0.5, 50.0),
        );
        let start = Joints::from_slice(&[0; 3].map(|_| rng.uniform(-1.0, 1.0))).unwrap();
        let goal = Joints::from_slice(&[0; 3].map(|_| rng.uniform(-1.0, 1.0))).unwrap();
        let min_duration = if rng.next_f64() < 0.5 {
            0.0
        } else {
            rng.uniform(0.0, 10.0)
        };
        let mut generator = JointGenerator::new(start, v, a).with_jerk_limits(Some(j));
        let duration = generator.move_to(goal, min_duration).unwrap();
        assert!(duration >= min_duration);
        let mut q = vec![start];
        // Until one tick past the end, so that the last differences see the arrival at rest.
        for _ in 0..(duration / dt) as usize + 3 {
            q.push(generator.advance(dt).0);
        }
        assert_eq!(*q.last().unwrap(), goal);
        let rounding = 8.0 * f64::EPSILON / (dt * dt * dt);
        for i in 0..3 {
            let x: Vec<f64> = q.iter().map(|q| q[i]).collect();
            let [vel, acc, jerk] = difference_peaks(&x, dt);
            assert!(within(vel, v[i], 0.0), "joint {i}: v {vel} > {}", v[i]);
            assert!(within(acc, a[i], 1e-12), "joint {i}: a {acc} > {}", a[i]);
            assert!(
                within(jerk, j[i], rounding),
                "joint {i}: j {jerk} > {}",
                j[i]
            );
        }
    }
}

/// Hostile durations (the protocol's T) on jerk-limited moves: a NaN or infinite one is
/// refused, ±1e308 give a move, and every command stays finite and within the joint limits.
#[test]
fn jerk_limited_moves_survive_hostile_durations() {
    let config = common::robot("ranger-mk1-jerk");
    let chain = armgate_core::kinematics::Chain::new(&config);
    for duration in [
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        1e308,
        -1e308,
        1e-300,
    ] {
        for mode in [Mode::Joint, Mode::Cartesian] {
            let mut ctrl = Controller::new(&config);
            ctrl.step(0.0, &MK1_READY).unwrap();
            ctrl.set_mode(mode).unwrap();
            let pose = ctrl.step(0.0, &MK1_READY).unwrap().measured_pose;
            let started = match mode {
                Mode::Joint => ctrl.move_joints(&[1.6, 0.65, -0.35, 0.2, 1.8, 0.1], duration),
                _ => {
                    let goal = Frame::from_parts(
                        (pose.translation.vector + Vector3::new(0.01, 0.0, -0.01)).into(),
                        pose.rotation,
                    );
                    ctrl.move_cartesian(goal, duration)
                }
            };
            assert_eq!(
                started.is_ok(),
                duration.is_finite(),
                "{duration} {started:?}"
            );
            let mut q = Joints::from_slice(&MK1_READY).unwrap();
            for k in 1..300 {
                let out = ctrl.step(f64::from(k), &q).unwrap();
                let command = out.command.unwrap();
                assert!(
                    command.is_finite() && chain.within_limits(&command),
                    "{command:?}"
                );
                q = command;
            }
        }
    }
}

fn config_pose(config: &ValidRobot, q: &Joints) -> Frame {
    armgate_core::kinematics::Chain::new(config)
        .forward(q)
        .unwrap()
}
