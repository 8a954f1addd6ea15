//! NaN, ±Inf and 1e308 (±f32::MAX on the wire) at every public entry point of the tick: nothing
//! panics, nothing non-finite is ever commanded, and every refusal is typed.
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]
// The seed deployed rounded angles such as 1.5708.
#![allow(clippy::approx_constant)]

mod common;
mod drives_rig;

use armgate_core::command::CommandHandler;
use armgate_core::config::ValidRobot;
use armgate_core::kinematics::{Joints, KinematicsError};
use armgate_core::motion::{Controller, JointLimiter, Mode, Refusal};
use armgate_core::sim::{ArmModel, SimulatedDrives};
use armgate_core::sim::{IdealArm, RateLimitedArm};
use armgate_protocol::client::Command;
use armgate_protocol::client::{JointBound, PathPoint};

const HOSTILE: [f64; 5] = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e308, -1e308];
const MK1_READY: [f64; 6] = [1.5708, 0.6, -0.4, 0.2, 1.8, 0.1];

fn mk1() -> ValidRobot {
    common::robot("ranger-mk1")
}

fn with(q: &[f64], joint: usize, value: f64) -> Vec<f64> {
    let mut q = q.to_vec();
    q[joint] = value;
    q
}

/// A controller in `mode` that has seen the arm at `MK1_READY`.
fn controller(mode: Mode) -> Controller {
    let mut ctrl = Controller::new(&mk1());
    ctrl.step(0.0, &MK1_READY).unwrap();
    ctrl.set_mode(mode).unwrap();
    ctrl
}

/// Ticks `ctrl` on an ideal arm and checks every command is finite, and within the limits
/// unless the previous one was not (the rate limit then walks it back; it never jumps).
fn run_finite(ctrl: &mut Controller, ticks: usize) {
    let chain = ctrl.chain().clone();
    let mut q = ctrl.command().map_or(MK1_READY.to_vec(), |c| c.to_vec());
    for k in 0..ticks {
        let was_inside = chain.within_limits(&q);
        let out = ctrl.step(k as f64 * 0.01944, &q).unwrap();
        if let Some(c) = out.command {
            assert!(c.is_finite(), "tick {k}: {c:?}");
            assert!(!was_inside || chain.within_limits(&c), "tick {k}: {c:?}");
            q = c.to_vec();
        }
    }
}

#[test]
fn controller_step_refuses_non_finite_measurements_and_survives_huge_ones() {
    for mode in [Mode::Off, Mode::Joint, Mode::Cartesian] {
        for joint in 0..6 {
            for value in HOSTILE {
                let mut ctrl = controller(mode);
                let measured = with(&MK1_READY, joint, value);
                match ctrl.step(1.0, &measured) {
                    Err(e) => {
                        assert!(!value.is_finite(), "{value}: {e:?}");
                        assert_eq!(e, KinematicsError::NonFiniteJoints);
                    }
                    Ok(out) => {
                        assert!(value.is_finite());
                        // A huge measurement is taken as it is; the command stays finite.
                        assert!(out.command.is_none_or(|c| c.is_finite()), "{out:?}");
                    }
                }
                // Back to sane measurements: the controller carries on.
                run_finite(&mut ctrl, 5);
            }
        }
    }
}

#[test]
fn controller_step_time_is_only_a_stamp() {
    for value in HOSTILE {
        let mut ctrl = controller(Mode::Joint);
        ctrl.move_joints(&with(&MK1_READY, 0, 1.0), 0.0).unwrap();
        let out = ctrl.step(value, &MK1_READY).unwrap();
        assert!(out.command.unwrap().is_finite());
    }
}

#[test]
fn joint_requests_refuse_hostile_goals_and_durations() {
    for joint in 0..6 {
        for value in HOSTILE {
            let goal = with(&MK1_READY, joint, value);
            let mut ctrl = controller(Mode::Joint);
            let expected = if value.is_finite() {
                // ±1e308: beyond the maximum or the minimum, named.
                let above = value > 0.0;
                let chain = ctrl.chain();
                let limit = if above { chain.max() } else { chain.min() }[joint];
                Refusal::OutsideJointLimits(JointBound::new(joint, above, limit, PathPoint::Goal))
            } else {
                Refusal::InvalidNumber
            };
            assert_eq!(ctrl.move_joints(&goal, 1.0), Err(expected), "{value}");
            assert_eq!(ctrl.set_joint_via(0, &goal, 1.0), Err(expected));
            assert_eq!(ctrl.check_joint_goal(&goal), Err(expected));
        }
    }
    let goal = with(&MK1_READY, 0, 1.0);
    for duration in HOSTILE {
        let mut ctrl = controller(Mode::Joint);
        if duration.is_finite() {
            // 1e308 s is a (very slow) motion; -1e308 means as fast as the limits allow.
            ctrl.move_joints(&goal, duration).unwrap();
            ctrl.set_joint_via(1, &goal, duration).unwrap();
            run_finite(&mut ctrl, 200);
        } else {
            assert_eq!(
                ctrl.move_joints(&goal, duration),
                Err(Refusal::InvalidNumber)
            );
            assert_eq!(
                ctrl.set_joint_via(0, &goal, duration),
                Err(Refusal::InvalidNumber)
            );
        }
    }
}

#[test]
fn the_limiter_never_outputs_a_non_finite_or_out_of_range_value() {
    let robot = mk1();
    let limiter = JointLimiter::new(&robot);
    let previous = Joints::from_slice(&MK1_READY).unwrap();
    let max_step: Vec<f64> = robot
        .joints
        .iter()
        .map(|j| j.max_rate * robot.control_period)
        .collect();
    for joint in 0..6 {
        for value in HOSTILE {
            let request = Joints::from_slice(&with(&MK1_READY, joint, value)).unwrap();
            let limited = limiter.limit(&request, &previous, &Joints::zeros(6));
            assert!(limited.q.is_finite(), "{value}: {:?}", limited.q);
            assert!(limited.position_clamped, "{value}");
            for ((q, p), (step, j)) in limited
                .q
                .iter()
                .zip(previous.iter())
                .zip(max_step.iter().zip(&robot.joints))
            {
                assert!((q - p).abs() <= step + 1e-15 && j.min <= *q && *q <= j.max);
            }
            // A NaN or infinite request holds the joint where it was.
            if !value.is_finite() {
                assert_eq!(limited.q[joint], MK1_READY[joint]);
            }
            // No hostile step passes the rate check.
            assert_eq!(limiter.rate_ratio(&request, &previous), {
                let step = (value - MK1_READY[joint]).abs() / max_step[joint];
                if step.is_nan() { f64::INFINITY } else { step }
            });
        }
    }
}

#[test]
fn chain_entry_points_refuse_or_stay_finite() {
    // The hybrid arm has prismatic joints: a huge slide overflows J·Jᵀ to NaN, and
    // manipulability must still be a number (zero).
    for name in ["ranger-mk1", "hybrid"] {
        let robot = common::robot(name);
        let ctrl = Controller::new(&robot);
        let chain = ctrl.chain();
        let home = robot.home();
        for joint in 0..chain.dof() {
            for value in HOSTILE {
                let q = with(&home, joint, value);
                let m = chain.manipulability(&q);
                if value.is_finite() {
                    let m = m.unwrap();
                    assert!(m >= 0.0 && m.is_finite(), "{name} {joint} {value}: {m}");
                } else {
                    assert_eq!(m, Err(KinematicsError::NonFiniteJoints));
                    assert!(chain.forward(&q).is_err() && chain.jacobian(&q).is_err());
                }
            }
        }
    }
}

#[test]
fn simulated_arms_take_no_time_for_a_hostile_step() {
    let q0 = Joints::from_slice(&MK1_READY).unwrap();
    let target = Joints::from_slice(&with(&MK1_READY, 0, 1.0)).unwrap();
    let limits = Joints::from_slice(&[1.0; 6]).unwrap();
    for dt in [
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        -1e308,
        -0.01,
        0.0,
    ] {
        let mut arm = RateLimitedArm::new(q0, limits, limits);
        arm.step(Some(&target), dt);
        assert_eq!(arm.measured(), q0, "{dt}");
        let mut drives = SimulatedDrives::new(ArmModel::RateLimited(arm));
        drives.apply(Some(&target), dt);
        assert_eq!(drives.measured().to_vec(), q0.to_vec());
    }
    // Hostile commands are ignored by both arms.
    for value in HOSTILE.iter().filter(|v| !v.is_finite()) {
        let bad = Joints::from_slice(&with(&MK1_READY, 2, *value)).unwrap();
        let mut arm = RateLimitedArm::new(q0, limits, limits);
        arm.step(Some(&bad), 0.01);
        assert_eq!(arm.measured(), q0);
    }
    // 1e308 s is a step, not a panic.
    let mut arm = RateLimitedArm::new(q0, limits, limits);
    arm.step(Some(&target), 1e308);
}

/// Every request, every value field, every hostile f32: the handler answers, and the commands
/// of the ticks that follow are finite and within the limits.
#[test]
fn the_handler_survives_hostile_numbers_in_every_field_of_every_command() {
    let robot = mk1();
    let chain = Controller::new(&robot).chain().clone();
    let wire = [
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::MAX,
        -f32::MAX,
    ];
    for command in Command::ALL {
        for mode in [1.0f32, 2.0] {
            for field in 0..7 {
                for value in wire {
                    let arm = IdealArm::new(Joints::from_slice(&MK1_READY).unwrap());
                    let mut drives = SimulatedDrives::new(ArmModel::Ideal(arm));
                    let mut handler = CommandHandler::new(&robot);
                    let mut now = 0.0;
                    let mut tick = |handler: &mut CommandHandler, drives: &mut SimulatedDrives| {
                        now += robot.control_period;
                        let out = handler.tick(now, &drives.measured(), drives).unwrap();
                        if let Some(c) = out.command {
                            assert!(c.is_finite() && chain.within_limits(&c), "{c:?}");
                        }
                        drives.apply(out.command.as_ref(), robot.control_period);
                    };
                    tick(&mut handler, &mut drives);
                    handler.handle(
                        &datagram(b"CM", [mode, 0., 0., 0., 0., 0., 0.]),
                        &mut drives,
                    );
                    tick(&mut handler, &mut drives);
                    // A sane request first, so that BG/jB/VE/jE have something to start.
                    let mut values = [0.0f32; 7];
                    for (v, q) in values.iter_mut().zip(MK1_READY) {
                        *v = q as f32;
                    }
                    values[field] = value;
                    let reply = handler.handle(&datagram(&command.chars(), values), &mut drives);
                    assert_ne!(reply[..2], [0, 0], "{command:?}");
                    for follow_up in [b"BG", b"jB", b"VE", b"jE"] {
                        handler.handle(&datagram(follow_up, [0.0; 7]), &mut drives);
                    }
                    for _ in 0..20 {
                        tick(&mut handler, &mut drives);
                    }
                }
            }
        }
    }
}

#[test]
fn the_drive_manager_refuses_hostile_commands_whole() {
    let mut rig = drives_rig::Rig::new(mk1());
    rig.start();
    let before = rig.drive_positions();
    let mut rejected = rig.manager().stats().commands_rejected;
    // The manager stepped by hand (the controller never sends such commands), on the bus's
    // time from the rig's last tick on.
    let mut now = rig.now;
    let mut step = |rig: &mut drives_rig::Rig, command: Option<&Joints>| {
        now += rig.period;
        let (manager, bus) = rig.cycle.drives_mut().split_mut();
        assert!(armgate_core::drives::CanBus::advance_to(bus, now));
        manager.cycle(now, command, bus);
    };
    for joint in 0..6 {
        for value in HOSTILE {
            let bad = Joints::from_slice(&with(&before, joint, value)).unwrap();
            step(&mut rig, Some(&bad));
            // 1e308 rad is beyond 32-bit encoder counts: refused like NaN, all joints held.
            rejected += 1;
            assert_eq!(rig.manager().stats().commands_rejected, rejected, "{value}");
            assert!(rig.manager().fault().is_none());
        }
    }
    for _ in 0..20 {
        step(&mut rig, None);
    }
    assert!(rig.manager().fault().is_none());
    for (now, was) in rig.drive_positions().iter().zip(&before) {
        assert!((now - was).abs() < 1e-3, "{now} {was}");
    }
}

fn datagram(cmd: &[u8; 2], values: [f32; 7]) -> [u8; 31] {
    let mut d = [0u8; 31];
    d[..2].copy_from_slice(cmd);
    for (k, v) in values.iter().enumerate() {
        d[2 + 4 * k..6 + 4 * k].copy_from_slice(&v.to_le_bytes());
    }
    d
}
