//! Generators, sequences, limiters, the mode switch and the control step (spec §4, §5).
#![allow(
    clippy::approx_constant,
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod common;

use armgate_core::config::ValidRobot;
use armgate_core::kinematics::{Chain, Joints};
use armgate_core::math::{self, Frame, Rotation3, Vector3};
use armgate_core::motion::{
    CartesianGenerator, Controller, JointGenerator, JointLimiter, Mode, Refusal, Shape, StepOutput,
    StopCause, Trapezoid,
};
use armgate_core::rng::SplitMix64;
use armgate_core::sim::RateLimitedArm;
use armgate_protocol::client::{JointBound, PathPoint};

use common::arm_rig::ArmRig as Rig;

const MK1_HOME: [f64; 6] = [1.5708, 0.0, 1.5708, 0.0, 1.5708, 0.0];
/// A comfortable ranger-mk1 pose in front of the base, away from limits and singularities.
const MK1_READY: [f64; 6] = [1.5708, 0.6, -0.4, 0.2, 1.8, 0.1];

fn mk1_fast() -> ValidRobot {
    common::robot("ranger-mk1")
        .edit(|config| {
            config.cartesian.max_velocity = [0.1, 0.1, 0.1, 0.3, 0.3, 0.3];
            config.cartesian.max_acceleration = [0.2, 0.2, 0.2, 0.5, 0.5, 0.5];
            // Joints that can follow these Cartesian limits (every command is held to the
            // joints' acceleration limits).
            for j in config.joints.iter_mut() {
                j.max_rate = 2.0;
                j.drive.max_speed = 2.0;
                j.max_acceleration = 4.0;
            }
        })
        .unwrap()
}

#[test]
fn joint_generator_is_synchronised_within_limits_and_exact_at_the_end() {
    let v = Joints::from_slice(&[0.5, 0.2, 1.0]).unwrap();
    let a = Joints::from_slice(&[1.0, 0.5, 2.0]).unwrap();
    let mut generator = JointGenerator::new(Joints::zeros(3), v, a);
    let goal = Joints::from_slice(&[0.3, -0.7, 0.1]).unwrap();
    let duration = generator.move_to(goal, 0.0).unwrap();
    assert_eq!(generator.move_to(goal, 0.0), Err(Refusal::Busy));
    let dt = 0.001;
    let (mut prev, mut prev_v) = (Joints::zeros(3), [0.0; 3]);
    let mut t = 0.0;
    let mut finished_at = None;
    while finished_at.is_none() {
        t += dt;
        let (q, finished) = generator.advance(dt);
        for i in 0..3 {
            let vel = (q[i] - prev[i]) / dt;
            assert!(vel.abs() <= v[i] * (1.0 + 1e-9), "joint {i} speed {vel}");
            if t > 2.0 * dt && t < duration - 2.0 * dt {
                assert!(
                    ((vel - prev_v[i]) / dt).abs() <= a[i] * 1.01,
                    "joint {i} acceleration"
                );
            }
            prev_v[i] = vel;
            // All joints progress by the same fraction: synchronised, straight in joint space.
            let fraction = q[i] / goal[i];
            assert!((fraction - q[0] / goal[0]).abs() < 1e-12);
        }
        prev = q;
        if finished {
            finished_at = Some(t);
        }
    }
    assert!((finished_at.unwrap() - duration).abs() <= dt);
    assert_eq!(generator.setpoint(), goal, "not exactly at the goal");
    // The minimum duration is honoured.
    let d = generator.move_to(Joints::zeros(3), 30.0).unwrap();
    assert_eq!(d, 30.0);
    assert!(!generator.advance(29.9).1);
    assert_eq!(generator.advance(0.1), (Joints::zeros(3), true));
}

#[test]
fn trapezoid_never_exceeds_its_limits_on_random_moves() {
    let mut rng = SplitMix64::new(21);
    for _ in 0..1000 {
        let (s0, s1) = (rng.uniform(-2.0, 2.0), rng.uniform(-2.0, 2.0));
        let (v, a) = (rng.uniform(0.01, 2.0), rng.uniform(0.01, 5.0));
        let min = rng.uniform(0.0, 10.0);
        let p = Trapezoid::plan(s0, s1, v, a).stretched(min);
        assert!(
            p.peak_velocity() <= v * (1.0 + 1e-12) && p.peak_acceleration() <= a * (1.0 + 1e-12)
        );
        assert!(p.duration() >= min.min(Trapezoid::plan(s0, s1, v, a).duration()) - 1e-12);
        assert_eq!(p.position(p.duration()), s1);
        assert_eq!(p.position(0.0), s0);
    }
}

#[test]
fn cartesian_path_is_straight_and_orientation_turns_monotonically_about_a_fixed_axis() {
    let v = [0.1, 0.05, 0.2, 0.3, 0.2, 0.1];
    let a = [0.2, 0.1, 0.3, 0.5, 0.4, 0.3];
    let start = Frame::from_parts(
        Vector3::new(0.4, 0.1, 0.5).into(),
        Rotation3::from_euler_angles(0.1, -0.2, 0.3),
    );
    let goal = Frame::from_parts(
        Vector3::new(0.1, 0.3, 0.2).into(),
        Rotation3::from_euler_angles(-0.5, 0.4, 1.2),
    );
    let mut generator = CartesianGenerator::new(start, v, a);
    let duration = generator.move_to(goal, 0.0).unwrap();
    let axis = math::diff(&start, &goal).fixed_rows::<3>(3).into_owned();
    let axis = axis * (1.0 / axis.norm());
    let line = goal.translation.vector - start.translation.vector;
    let mut prev_angle = f64::INFINITY;
    let mut prev_pos = start.translation.vector;
    let dt = 0.002;
    for k in 1..=((duration / dt) as usize + 2) {
        let (sp, finished) = generator.advance_to(k as f64 * dt);
        // On the line through start and goal.
        let off = (sp.translation.vector - start.translation.vector)
            .cross(&line)
            .norm()
            / line.norm();
        assert!(off < 1e-12, "{off} m off the line");
        for (i, d) in (sp.translation.vector - prev_pos).iter().enumerate() {
            assert!((d / dt).abs() <= v[i] * (1.0 + 1e-9), "axis {i} too fast");
        }
        prev_pos = sp.translation.vector;
        // Turning about the fixed axis, monotonically towards the goal.
        let turned = math::diff(&start, &sp).fixed_rows::<3>(3).into_owned();
        assert!(turned.cross(&axis).norm() < 1e-9, "axis drifted");
        let angle = math::diff(&sp, &goal).fixed_rows::<3>(3).norm();
        assert!(angle <= prev_angle + 1e-12, "orientation went back");
        prev_angle = angle;
        if finished {
            assert_eq!(sp, goal);
            return;
        }
    }
    panic!("never finished");
}

#[test]
fn cartesian_move_reaches_the_goal_through_ik_to_1e9() {
    let config = mk1_fast();
    let mut rig = Rig::new(&config, &MK1_READY);
    rig.ctrl.set_mode(Mode::Cartesian).unwrap();
    let start = rig.pose();
    let goal = Frame::from_parts(
        (start.translation.vector + Vector3::new(0.05, -0.08, 0.1)).into(),
        Rotation3::from_axis_angle(&Vector3::z_axis(), 0.2) * start.rotation,
    );
    rig.ctrl.move_cartesian(goal, 2.0).unwrap();
    let outs = rig.settle(2000);
    assert!(outs.iter().any(|o| o.events.motion_finished));
    assert!(
        outs.iter()
            .all(|o| !o.events.ik_divergence && !o.events.rate_limit)
    );
    let reached = math::diff(&rig.pose(), &goal);
    assert!(
        reached.fixed_rows::<3>(0).norm() < 1e-9 && reached.fixed_rows::<3>(3).norm() < 1e-9,
        "{reached:?}"
    );
}

#[test]
fn refusals_say_why() {
    let config = mk1_fast();
    let mut ctrl = Controller::new(&config);
    assert_eq!(ctrl.set_mode(Mode::Joint), Err(Refusal::NotReady));
    let mut rig = Rig::new(&config, &MK1_READY);
    let pose = rig.pose();
    assert_eq!(rig.ctrl.move_cartesian(pose, 0.0), Err(Refusal::WrongMode));
    assert_eq!(
        rig.ctrl.move_joints(&MK1_READY, 0.0),
        Err(Refusal::WrongMode)
    );
    rig.ctrl.set_mode(Mode::Joint).unwrap();
    assert_eq!(rig.ctrl.move_cartesian(pose, 0.0), Err(Refusal::WrongMode));
    assert_eq!(
        rig.ctrl.move_joints(&MK1_READY[..5], 0.0),
        Err(Refusal::WrongJointCount)
    );
    let mut nan = MK1_READY;
    nan[3] = f64::NAN;
    assert_eq!(rig.ctrl.move_joints(&nan, 0.0), Err(Refusal::InvalidNumber));
    assert_eq!(
        rig.ctrl.move_joints(&MK1_READY, f64::INFINITY),
        Err(Refusal::InvalidNumber)
    );
    let mut beyond = MK1_READY;
    beyond[4] = 0.0; // joint 5 range is [0.785, 3.926]
    assert_eq!(
        rig.ctrl.move_joints(&beyond, 0.0),
        Err(Refusal::OutsideJointLimits(JointBound::new(
            4,
            false,
            0.785,
            PathPoint::Goal
        )))
    );
    assert_eq!(rig.ctrl.start_joint_sequence(), Err(Refusal::NoGoal));
    let mut target = MK1_READY;
    target[0] += 0.2;
    rig.ctrl.move_joints(&target, 0.0).unwrap();
    assert_eq!(rig.ctrl.move_joints(&MK1_READY, 0.0), Err(Refusal::Busy));
    assert_eq!(
        rig.ctrl.set_joint_via(20, &MK1_READY, 0.0),
        Err(Refusal::IndexOutOfRange)
    );
    rig.ctrl.stop(StopCause::Stop);
    rig.ctrl.set_mode(Mode::Cartesian).unwrap();
    let mut bad = pose;
    bad.translation.vector.x = f64::NAN;
    assert_eq!(
        rig.ctrl.move_cartesian(bad, 0.0),
        Err(Refusal::InvalidNumber)
    );
    // Inside the column around the base.
    let inside = Frame::from_parts(Vector3::new(0.0, 0.0, 0.2).into(), pose.rotation);
    assert_eq!(
        rig.ctrl.move_cartesian(inside, 0.0),
        Err(Refusal::OutsideWorkspace)
    );
    assert_eq!(
        rig.ctrl.set_cartesian_via(0, inside, 0.0),
        Err(Refusal::OutsideWorkspace)
    );
    assert_eq!(rig.ctrl.start_cartesian_sequence(), Err(Refusal::NoGoal));
    let circle = Shape::Circle {
        radius: 0.1,
        period: 5.0,
        axis_i: 0,
        axis_j: 0,
    };
    assert_eq!(rig.ctrl.start_shape(circle), Err(Refusal::InvalidNumber));
}

#[test]
fn joint_sequence_runs_all_points_in_order_and_stops_at_the_first_gap() {
    let config = mk1_fast();
    let mut rig = Rig::new(&config, &MK1_READY);
    rig.ctrl.set_mode(Mode::Joint).unwrap();
    let points: Vec<[f64; 6]> = (0..4)
        .map(|k| {
            let mut q = MK1_READY;
            q[0] += 0.05 * (k + 1) as f64;
            q[2] -= 0.03 * (k + 1) as f64;
            q
        })
        .collect();
    for (k, q) in points.iter().enumerate() {
        rig.ctrl.set_joint_via(k, q, 0.5).unwrap();
    }
    // Slot 5 after a gap at 4 must never be visited.
    let mut far = MK1_READY;
    far[0] -= 1.0;
    rig.ctrl.set_joint_via(5, &far, 0.0).unwrap();
    rig.ctrl.start_joint_sequence().unwrap();
    assert_eq!(rig.ctrl.start_joint_sequence(), Err(Refusal::Busy));
    let mut visited = Vec::new();
    let mut finished = false;
    for _ in 0..5000 {
        let out = rig.tick();
        let q = rig.arm.measured();
        let at = points
            .iter()
            .position(|p| p.iter().zip(q.iter()).all(|(a, b)| a == b));
        if let Some(k) = at
            && visited.last() != Some(&k)
        {
            visited.push(k);
        }
        assert!(
            q[0] > MK1_READY[0] - 1e-12,
            "moved towards the point after the gap"
        );
        if out.events.sequence_finished {
            finished = true;
            break;
        }
    }
    assert!(finished);
    assert_eq!(visited, vec![0, 1, 2, 3]);
    assert!(!rig.ctrl.is_moving());
}

#[test]
fn cartesian_sequence_visits_every_point() {
    let config = mk1_fast();
    let mut rig = Rig::new(&config, &MK1_READY);
    rig.ctrl.set_mode(Mode::Cartesian).unwrap();
    let start = rig.pose();
    let corners = [
        Vector3::new(0.05, 0.0, 0.0),
        Vector3::new(0.05, 0.0, 0.05),
        Vector3::new(0.0, 0.0, 0.05),
        Vector3::zeros(),
    ];
    for (k, c) in corners.iter().enumerate() {
        rig.ctrl
            .set_cartesian_via(
                k,
                Frame::from_parts((start.translation.vector + *c).into(), start.rotation),
                0.0,
            )
            .unwrap();
    }
    rig.ctrl.start_cartesian_sequence().unwrap();
    let mut hits = 0;
    for _ in 0..20_000 {
        let out = rig.tick();
        let p = rig.pose().translation.vector - start.translation.vector;
        if corners.get(hits).is_some_and(|c| (p - *c).norm() < 1e-9) {
            hits += 1;
        }
        if out.events.sequence_finished {
            break;
        }
    }
    assert_eq!(hits, 4);
    assert!(!rig.ctrl.is_moving());
}

#[test]
fn joint_limiter_clamps_range_and_rate_and_reports() {
    let config = common::robot("ranger-mk1");
    let limiter = JointLimiter::new(&config);
    let prev = Joints::from_slice(&MK1_HOME).unwrap();
    // At a limit exactly: no event (the seed raised one every tick).
    let mut at = MK1_HOME;
    at[1] = -0.785;
    let mut prev_at = prev;
    prev_at[1] = -0.785;
    let rest = Joints::zeros(6);
    let l = limiter.limit(&Joints::from_slice(&at).unwrap(), &prev_at, &rest);
    assert!(!l.position_clamped && !l.rate_clamped);
    let mut beyond = at;
    beyond[1] = -0.9;
    let l = limiter.limit(&Joints::from_slice(&beyond).unwrap(), &prev_at, &rest);
    assert!(l.position_clamped && l.q[1] == -0.785);
    // Rate: 0.2 rad/s × 0.01944 s per tick, for a joint already moving at it.
    let mut jump = MK1_HOME;
    jump[0] += 0.5;
    let mut cruising = rest;
    cruising[0] = 0.2;
    let l = limiter.limit(&Joints::from_slice(&jump).unwrap(), &prev, &cruising);
    assert!(l.rate_clamped && !l.position_clamped && !l.acceleration_clamped);
    assert!((l.q[0] - (MK1_HOME[0] + 0.2 * 0.01944)).abs() < 1e-12);
    // Acceleration: from rest, the step grows by at most 0.5 rad/s² × 0.01944² per tick;
    // at 0.2 rad/s, a request to stop dead is eased by as much.
    let l = limiter.limit(&Joints::from_slice(&jump).unwrap(), &prev, &rest);
    assert!(l.acceleration_clamped);
    assert!((l.q[0] - (MK1_HOME[0] + 0.5 * 0.01944 * 0.01944)).abs() < 1e-12);
    let l = limiter.limit(&prev, &prev, &cruising);
    assert!(l.acceleration_clamped && !l.rate_clamped);
    let step = 0.2 * 0.01944 - 0.5 * 0.01944 * 0.01944;
    assert!((l.q[0] - (MK1_HOME[0] + step)).abs() < 1e-12);
}

#[test]
fn boxes_block_cartesian_moves_and_allow_joint_moves_out() {
    // Two poses on an arc about the base axis; a box around the chord's midpoint blocks the
    // straight Cartesian path and contains the arc's midpoint.
    let config = mk1_fast();
    let chain = Chain::new(&config);
    let q_a = MK1_READY;
    let mut q_b = MK1_READY;
    q_b[0] += 0.5;
    let mut q_mid = MK1_READY;
    q_mid[0] += 0.25;
    let (pa, pb) = (chain.forward(&q_a).unwrap(), chain.forward(&q_b).unwrap());
    let m = (pa.translation.vector + pb.translation.vector) * 0.5;
    let half = 0.05;
    let box_around_m = [
        m.x - half,
        m.x + half,
        m.y - half,
        m.y + half,
        m.z - half,
        m.z + half,
    ];
    let config = config
        .edit(|config| {
            config.workspace.boxes.clear();
            config.workspace.boxes.push(box_around_m).unwrap();
        })
        .unwrap();
    let in_box = |p: Vector3<f64>| (p - m).iter().all(|c| c.abs() < half);
    assert!(in_box(chain.forward(&q_mid).unwrap().translation.vector));

    // Cartesian: the move is refused up front, with where the line enters the box.
    let mut rig = Rig::new(&config, &q_a);
    rig.ctrl.set_mode(Mode::Cartesian).unwrap();
    match rig.ctrl.move_cartesian(pb, 0.0) {
        Err(Refusal::CrossesBox(percent)) => assert!((20..50).contains(&percent), "{percent}"),
        other => panic!("{other:?}"),
    }
    // Without the check, the move is aborted at the wall; no set-point inside ever reaches
    // the IK.
    let config = config.edit(|c| c.ik.check_lines = false).unwrap();
    let mut rig = Rig::new(&config, &q_a);
    rig.ctrl.set_mode(Mode::Cartesian).unwrap();
    rig.ctrl.move_cartesian(pb, 0.0).unwrap();
    let outs = rig.settle(20_000);
    assert!(outs.iter().any(|o| o.events.workspace_limit));
    assert_eq!(rig.ctrl.stop_cause().0, Some(StopCause::Workspace));
    assert!(
        outs.iter()
            .all(|o| !in_box(o.setpoint.unwrap().translation.vector))
    );
    assert!(
        !in_box(rig.pose().translation.vector)
            && (rig.pose().translation.vector - pb.translation.vector).norm() > 0.05
    );
    // A goal inside the box is refused outright.
    let inside = Frame::from_parts(m.into(), pa.rotation);
    assert_eq!(
        rig.ctrl.move_cartesian(inside, 0.0),
        Err(Refusal::OutsideWorkspace)
    );

    // Joint mode: driving into the box is refused up front, with where along the way.
    rig.ctrl.set_mode(Mode::Joint).unwrap();
    match rig.ctrl.move_joints(&q_mid, 0.0) {
        Err(Refusal::CrossesBox(percent)) => assert!((1..100).contains(&percent), "{percent}"),
        other => panic!("{other:?}"),
    }
    // An arm already inside (after a recalibration, at start-up) may drive out.
    let mut rig = Rig::new(&config, &q_mid);
    rig.ctrl.set_mode(Mode::Joint).unwrap();
    rig.settle(10);
    assert!(in_box(rig.pose().translation.vector));
    // Cartesian motion is refused while the arm is inside.
    rig.ctrl.set_mode(Mode::Cartesian).unwrap();
    assert_eq!(
        rig.ctrl.move_cartesian(pa, 0.0),
        Err(Refusal::ArmOutsideWorkspace)
    );
    rig.ctrl.set_mode(Mode::Joint).unwrap();
    rig.ctrl.move_joints(&q_a, 0.0).unwrap();
    let outs = rig.settle(20_000);
    assert_eq!(&rig.arm.measured()[..], &q_a[..]);
    assert!(!outs.last().unwrap().events.workspace_limit);
}

#[test]
fn mode_transitions_never_jump() {
    let config = mk1_fast();
    let mut rig = Rig::new(&config, &MK1_READY);
    let dt = config.control_period;
    let max_step: Vec<f64> = config
        .joints
        .iter()
        .map(|j| j.max_velocity * dt + 1e-12)
        .collect();
    let mut last: Option<Joints> = None;
    let mut check = |out: &StepOutput| {
        assert!(!out.events.rate_limit, "the pipeline itself jumped");
        if let (Some(prev), Some(cmd)) = (last, out.command) {
            for i in 0..6 {
                assert!(
                    (cmd[i] - prev[i]).abs() <= max_step[i].max(0.02),
                    "joint {i} jumped"
                );
            }
        }
        last = out.command.or(last);
    };
    // Off → joint: the first command is the measured position.
    rig.ctrl.set_mode(Mode::Joint).unwrap();
    let out = rig.tick();
    assert_eq!(out.command.unwrap(), rig.arm.measured());
    check(&out);
    let mut goal = MK1_READY;
    goal[0] += 0.3;
    goal[2] -= 0.2;
    rig.ctrl.move_joints(&goal, 0.0).unwrap();
    for _ in 0..60 {
        check(&rig.tick());
    }
    // Joint → Cartesian in mid-motion: comes to rest, then holds.
    rig.ctrl.set_mode(Mode::Cartesian).unwrap();
    for out in rig.settle(2_000) {
        check(&out);
    }
    let before = rig.ctrl.command().unwrap();
    let out = rig.tick();
    assert_eq!(out.command.unwrap(), before);
    check(&out);
    let pose = rig.pose();
    let goal_pose = Frame::from_parts(
        (pose.translation.vector + Vector3::new(0.0, -0.1, -0.05)).into(),
        pose.rotation,
    );
    rig.ctrl.move_cartesian(goal_pose, 0.0).unwrap();
    for _ in 0..60 {
        check(&rig.tick());
    }
    // Cartesian → joint in mid-motion, then off, then off → Cartesian.
    rig.ctrl.set_mode(Mode::Joint).unwrap();
    for _ in 0..5 {
        check(&rig.tick());
    }
    for out in rig.settle(2_000) {
        check(&out);
    }
    rig.ctrl.set_mode(Mode::Off).unwrap();
    assert_eq!(rig.tick().command, None);
    rig.ctrl.set_mode(Mode::Cartesian).unwrap();
    let out = rig.tick();
    let held = out.command.unwrap();
    assert!(
        held.iter()
            .zip(rig.arm.measured().iter())
            .all(|(a, b)| (a - b).abs() < 1e-9)
    );
    check(&out);
}

#[test]
fn shapes_trace_their_path_and_end_where_they_started() {
    let config = mk1_fast();
    let mut rig = Rig::new(&config, &MK1_READY);
    rig.ctrl.set_mode(Mode::Cartesian).unwrap();
    let start = rig.pose();
    let (radius, period) = (0.05, 4.0);
    rig.ctrl
        .start_shape(Shape::Circle {
            radius,
            period,
            axis_i: 0,
            axis_j: 2,
        })
        .unwrap();
    let centre = start.translation.vector - Vector3::x() * radius;
    let mut finish_requested = false;
    let mut ended = false;
    for k in 0..2000 {
        let out = rig.tick();
        let sp = out.setpoint.unwrap();
        assert!(((sp.translation.vector - centre).norm() - radius).abs() < 1e-12);
        assert!(
            (sp.translation.vector.y - start.translation.vector.y).abs() < 1e-12,
            "left the x-z plane"
        );
        assert!(!out.events.ik_divergence);
        let reached = (rig.pose().translation.vector - sp.translation.vector).norm();
        assert!(reached < 1e-9, "tick {k}: commanded path error {reached}");
        if k == 100 {
            rig.ctrl.finish_shape().unwrap();
            finish_requested = true;
        }
        if out.events.motion_finished {
            ended = true;
            break;
        }
    }
    assert!(finish_requested && ended);
    assert!(
        (rig.pose().translation.vector - start.translation.vector).norm() < 1e-9,
        "did not end at the start"
    );
    // A sinusoid along z, stopped at its next centre crossing.
    rig.ctrl
        .start_shape(Shape::Sinusoid {
            amplitude: 0.04,
            period: 3.0,
            axis: 2,
        })
        .unwrap();
    let mut peak: f64 = 0.0;
    for k in 0..2000 {
        let out = rig.tick();
        let off = out.setpoint.unwrap().translation.vector - start.translation.vector;
        assert!(off.x.abs() < 1e-12 && off.y.abs() < 1e-12);
        peak = peak.max(off.z.abs());
        if k == 120 {
            rig.ctrl.finish_shape().unwrap();
        }
        if out.events.motion_finished {
            break;
        }
    }
    assert!((peak - 0.04).abs() < 1e-4);
    assert!((rig.pose().translation.vector - start.translation.vector).norm() < 1e-9);
}

#[test]
fn rate_limited_arm_follows_a_stream_without_restarting_from_rest() {
    let v_max = Joints::from_slice(&[1.0]).unwrap();
    let a_max = Joints::from_slice(&[2.0]).unwrap();
    let mut arm = RateLimitedArm::new(Joints::zeros(1), v_max, a_max);
    let dt = 0.01;
    let speed = 0.5;
    let (mut prev_q, mut prev_v) = (0.0, 0.0);
    for k in 1..=400 {
        let cmd = Joints::from_slice(&[speed * k as f64 * dt]).unwrap();
        arm.step(Some(&cmd), dt);
        let q = arm.measured()[0];
        let v = (q - prev_q) / dt;
        assert!(v <= 1.0 + 1e-9 && ((v - prev_v) / dt).abs() <= 2.0 + 1e-6);
        (prev_q, prev_v) = (q, v);
        if k > 200 {
            // Steady state: moving with the stream at its speed, a bounded lag behind.
            assert!((v - speed).abs() < 0.05, "speed {v} at tick {k}");
            assert!(cmd[0] - q < 0.2);
        }
    }
    // Then it stops on a fixed command without overshooting.
    let target = Joints::from_slice(&[prev_q + 0.3]).unwrap();
    let mut max_q: f64 = 0.0;
    for _ in 0..300 {
        arm.step(Some(&target), dt);
        max_q = max_q.max(arm.measured()[0]);
    }
    assert_eq!(arm.measured()[0], target[0]);
    assert!(
        max_q <= target[0] + 1e-12,
        "overshoot {}",
        max_q - target[0]
    );
}

#[test]
fn the_readme_move_is_refused_up_front_where_the_run_would_stop() {
    // `armgate move 0.5 0.2 0.1 0 0 0 --time 5` from ranger-mk1's home: the straight line
    // needs joint 3 beyond its 1.600 maximum 3 % of the way (the seed's arm stopped there
    // after 3.9 s with WN22).
    let config = common::robot("ranger-mk1");
    let goal = at(
        Rotation3::from_euler_angles(0.0, 0.0, 0.0),
        Vector3::new(0.5, 0.2, 0.1),
    );
    let j3_max = JointBound::new(2, true, 1.6, PathPoint::Along(3));
    // Without the check the move starts, and stalls with joint 3 on that limit.
    let (rig, outs) = refused_where_the_unchecked_run_stops(
        &config,
        &MK1_HOME,
        goal,
        5.0,
        Refusal::OutsideJointLimits(j3_max),
    );
    assert_eq!(rig.ctrl.stop_cause().0, Some(StopCause::IkDivergence));
    let commands: Vec<_> = outs.iter().filter_map(|o| o.command).collect();
    let t = config.control_period;
    let mut peak = 0.0_f64;
    for w in commands.windows(3) {
        for (j, joint) in config.joints.iter().enumerate() {
            let a = (w[2][j] - 2.0 * w[1][j] + w[0][j]) / (t * t);
            peak = peak.max(a.abs() / joint.max_acceleration);
        }
    }
    // The stop that WN22 begins, like the run before it, stays within max_acceleration.
    assert!(peak <= 1.0 + 1e-6, "peak acceleration {peak} × max");
    assert!((rig.arm.measured()[2] - 1.6).abs() < 1e-3);
    assert!((rig.pose().translation.vector - goal.translation.vector).norm() > 0.5);
}

#[test]
fn lines_beyond_reach_or_through_boxes_are_refused_with_where() {
    let config = mk1_fast();
    let mut rig = Rig::new(&config, &MK1_READY);
    rig.ctrl.set_mode(Mode::Cartesian).unwrap();
    let here = rig.pose();
    // 1.8 m out, inside the bounds: lost part of the way there.
    let far = at(here.rotation, Vector3::new(1.8, 0.0, 0.6));
    match rig.ctrl.move_cartesian(far, 0.0) {
        Err(Refusal::Unreachable(PathPoint::Along(p))) => assert!((1..100).contains(&p)),
        Err(Refusal::OutsideJointLimits(JointBound { at, .. })) => {
            assert!(matches!(at, PathPoint::Along(_)), "{at:?}");
        }
        other => panic!("{other:?}"),
    }
    // Straight through the column around the base to the other side (midpoint at z = 0.15).
    let p = here.translation.vector;
    let across = at(here.rotation, Vector3::new(-p.x, -p.y, 0.3 - p.z));
    assert!(matches!(
        rig.ctrl.move_cartesian(across, 0.0),
        Err(Refusal::CrossesBox(_))
    ));
    // A reachable goal 5 cm up is accepted and reached.
    let up = at(
        here.rotation,
        here.translation.vector + Vector3::new(0.0, 0.0, 0.05),
    );
    rig.ctrl.move_cartesian(up, 0.0).unwrap();
    let outs = rig.settle(5_000);
    assert!(outs.iter().all(|o| !o.events.ik_divergence));
    assert!((rig.pose().translation.vector - up.translation.vector).norm() < 1e-6);
}

#[test]
fn a_sequence_is_refused_if_any_leg_cannot_be_followed() {
    let config = mk1_fast();
    let mut rig = Rig::new(&config, &MK1_READY);
    rig.ctrl.set_mode(Mode::Cartesian).unwrap();
    let here = rig.pose();
    let near = |dx, dz| {
        at(
            here.rotation,
            here.translation.vector + Vector3::new(dx, 0.0, dz),
        )
    };
    rig.ctrl.set_cartesian_via(0, near(0.05, 0.0), 0.0).unwrap();
    rig.ctrl
        .set_cartesian_via(1, near(0.05, 0.05), 0.0)
        .unwrap();
    // The third leg goes 1.8 m out.
    let far = at(here.rotation, Vector3::new(1.8, 0.0, 0.6));
    rig.ctrl.set_cartesian_via(2, far, 0.0).unwrap();
    let refusal = rig.ctrl.start_cartesian_sequence().unwrap_err();
    assert!(
        matches!(
            refusal,
            Refusal::Unreachable(_) | Refusal::OutsideJointLimits(_)
        ),
        "{refusal:?}"
    );
    assert!(!rig.ctrl.is_moving());
    // Fixed, it runs.
    rig.ctrl.set_cartesian_via(2, near(0.0, 0.05), 0.0).unwrap();
    rig.ctrl.start_cartesian_sequence().unwrap();
    let outs = rig.settle(20_000);
    assert!(outs.iter().any(|o| o.events.sequence_finished));
}

#[test]
fn accepted_random_lines_complete_and_refused_ones_do_not() {
    // Fixed seed: random goals up to 40 cm from random configurations of ranger-mk1. The
    // check's verdict must match a run without it (reach_bench prints the rate on every arm).
    let config = mk1_fast();
    let chain = Chain::new(&config);
    // Without the line check, and without the body's (which would stop some of these runs,
    // ER21, before the IK loses the line: this is about the IK).
    let unchecked = config
        .clone()
        .edit(|c| {
            c.ik.check_lines = false;
            c.collision.enabled = false;
        })
        .unwrap();
    let mut rng = SplitMix64::new(16);
    let (mut accepted, mut refused) = (0, 0);
    while accepted + refused < 40 {
        let q = chain.random_joints(&mut rng);
        let start = chain.forward(&q).unwrap();
        let dir = Vector3::new(
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
        );
        let goal = at(
            start.rotation,
            start.translation.vector + dir * (rng.uniform(0.02, 0.4) / dir.norm()),
        );
        let mut rig = Rig::new(&config, &q);
        rig.ctrl.set_mode(Mode::Cartesian).unwrap();
        let verdict = rig.ctrl.move_cartesian(goal, 0.0);
        // Lines refused for the joints' rates would be followed (slowed down) by the tick.
        if matches!(
            verdict,
            Err(Refusal::OutsideWorkspace
                | Refusal::ArmOutsideWorkspace
                | Refusal::CrossesBox(_)
                | Refusal::TooFast(..))
        ) {
            continue;
        }
        let mut run = Rig::new(&unchecked, &q);
        run.ctrl.set_mode(Mode::Cartesian).unwrap();
        run.ctrl.move_cartesian(goal, 0.0).unwrap();
        run.settle(20_000);
        let reached = (run.pose().translation.vector - goal.translation.vector).norm() < 1e-6;
        assert_eq!(verdict.is_ok(), reached, "{q:?} → {goal:?}: {verdict:?}");
        if reached {
            accepted += 1;
        } else {
            refused += 1;
        }
    }
    assert!(accepted >= 5 && refused >= 5, "{accepted} / {refused}");
}

/// Asserts that the line from joints `start` to `goal` is refused with `refusal` before the arm
/// moves; then runs it without the check (`ik.check_lines = false`), which must end in a
/// controlled stop with WN22, and returns that run.
fn refused_where_the_unchecked_run_stops(
    config: &ValidRobot,
    start: &[f64],
    goal: Frame,
    min_duration: f64,
    refusal: Refusal,
) -> (Rig, Vec<StepOutput>) {
    let mut rig = Rig::new(config, start);
    rig.ctrl.set_mode(Mode::Cartesian).unwrap();
    assert_eq!(rig.ctrl.move_cartesian(goal, min_duration), Err(refusal));
    assert!(!rig.ctrl.is_moving());
    // Without the line check, and without the body's (which would stop some of these runs,
    // ER21, before the IK loses the line: this is about the IK).
    let unchecked = config
        .clone()
        .edit(|c| {
            c.ik.check_lines = false;
            c.collision.enabled = false;
        })
        .unwrap();
    let mut rig = Rig::new(&unchecked, start);
    rig.ctrl.set_mode(Mode::Cartesian).unwrap();
    rig.ctrl.move_cartesian(goal, min_duration).unwrap();
    let outs = rig.settle(100_000);
    assert!(outs.iter().any(|o| o.events.ik_divergence));
    (rig, outs)
}

/// The frame with this rotation and position.
fn at(rotation: Rotation3<f64>, position: Vector3<f64>) -> Frame {
    Frame::from_parts(position.into(), rotation)
}

/// A line the tick follows slower where the joints need more than their rates (the move from
/// home of the qemu-bench tick): accepted as shipped (up to 100 times), refused with the joint
/// and where by a robot file that allows no slowing down.
#[test]
fn a_line_that_needs_slowing_down_is_refused_where_the_robot_file_says_so() {
    let config = common::robot("ranger-mk1");
    let home = config.home();
    let start = Rig::new(&config, &home).pose();
    let goal = at(
        Rotation3::from_euler_angles(0.0, 0.0, 0.1) * start.rotation,
        start.translation.vector + Vector3::new(0.05, -0.05, 0.05),
    );
    let mut rig = Rig::new(&config, &home);
    rig.ctrl.set_mode(Mode::Cartesian).unwrap();
    assert!(rig.ctrl.move_cartesian(goal, 4.0).is_ok());
    let strict = config.clone().edit(|c| c.ik.line_slowdown = 1.0).unwrap();
    let mut rig = Rig::new(&strict, &home);
    rig.ctrl.set_mode(Mode::Cartesian).unwrap();
    let refusal = rig.ctrl.move_cartesian(goal, 4.0);
    assert!(matches!(refusal, Err(Refusal::TooFast(..))), "{refusal:?}");
    assert!(!rig.ctrl.is_moving());
}

#[test]
fn the_half_turn_line_is_refused_up_front() {
    // The case: after the README's `armgate jmove 1.5708 0.4 1.2 0 1.2 0` the tool is
    // 6 cm from joint 1's axis (its wrist centre 1.5 cm), and the line to (0.1, 0.6, 0.9) with
    // roll-pitch-yaw (0, 1.57, 0) takes the wrist centre within 6 mm of the axis 3 % of the
    // way. Followed as the tick follows it, joint 1 swings 2.7 rad there and joint 6 with it,
    // into its limit 18 % of the way (the run aborted with WN22). The nearest IK solution a
    // sixteenth of the line ahead is on the other shoulder branch, 0.4 rad from the start:
    // the check took it for a step and accepted the line. Now it follows the swing in short
    // steps, and refuses the line with joint 6's limit and where, whatever the joints' rates.
    let start = [1.5708, 0.4, 1.2, 0.0, 1.2, 0.0];
    let goal = at(
        Rotation3::from_euler_angles(0.0, 1.57, 0.0),
        Vector3::new(0.1, 0.6, 0.9),
    );
    // The shipped limits, the Cartesian limits of armgate-sim's end-to-end tests, and joints
    // ten times as fast.
    let e2e = common::robot("ranger-mk1")
        .edit(|c| {
            c.cartesian.max_velocity = [0.1, 0.1, 0.1, 0.3, 0.3, 0.3];
            c.cartesian.max_acceleration = [0.2, 0.2, 0.2, 0.5, 0.5, 0.5];
        })
        .unwrap();
    for config in [common::robot("ranger-mk1"), e2e, mk1_fast()] {
        let rig = Rig::new(&config, &start);
        assert!((rig.pose().translation.vector.xy().norm() - 0.060).abs() < 1e-3);
        let j6_max = JointBound::new(5, true, 3.142, PathPoint::Along(18));
        // Without the check the tick follows the line: joint 1 swings, within its rate and
        // acceleration (slowed down), and the motion ends in a controlled stop with WN22.
        let (_, outs) = refused_where_the_unchecked_run_stops(
            &config,
            &start,
            goal,
            0.0,
            Refusal::OutsideJointLimits(j6_max),
        );
        let q: Vec<Joints> = outs.iter().filter_map(|o| o.command).collect();
        let swing = q
            .iter()
            .map(|c| (c[0] - start[0]).abs())
            .fold(0.0, f64::max);
        assert!(swing > 2.5, "joint 1 swung {swing} rad");
    }
}
