//! The drive manager's life cycle on the virtual bus with simulated Whistles (spec §6.4–§6.9).
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]
// The seed's home angles are written as it wrote them (1.5708), not as π/2.
#![allow(clippy::approx_constant)]

mod drives_rig;

use std::collections::BTreeSet;

use armgate_core::config::ValidRobot;
use armgate_core::drives::streaming::TARGET_LEAD;
use armgate_core::drives::{
    DriveFault, DriveSettings, DriveState, LifecycleError, UNKNOWN_TEMPERATURE,
};
use armgate_core::kinematics::Joints;
use armgate_core::motion::{Mode, Refusal, Shape, StopCause};
use armgate_protocol::can::interpreter::Request;
use armgate_protocol::can::{NmtState, NodeMessage};
use drives_rig::{Rig, robot};

const MK1_READY: [f64; 6] = [1.5708, 0.6, -0.4, 0.2, 1.8, 0.1];

/// ranger-mk1 with generator limits that make the motion worth streaming.
fn mk1_fast() -> ValidRobot {
    robot("ranger-mk1")
        .edit(|config| {
            config.cartesian.max_velocity = [0.1, 0.1, 0.1, 0.3, 0.3, 0.3];
            config.cartesian.max_acceleration = [0.2, 0.2, 0.2, 0.5, 0.5, 0.5];
            for joint in config.joints.iter_mut() {
                joint.max_velocity = 0.4;
                joint.max_acceleration = 1.0;
                joint.max_rate = 2.0;
                joint.drive.max_speed = 2.0;
            }
        })
        .unwrap()
}

/// A rig on `mk1_fast`, its drives started, `ticks` into a joint move towards `MK1_READY`.
fn moving(ticks: usize) -> Rig {
    let mut rig = Rig::new(mk1_fast());
    rig.start();
    rig.ctrl_mut().set_mode(Mode::Joint).unwrap();
    rig.ctrl_mut().move_joints(&MK1_READY, 0.0).unwrap();
    rig.ticks(ticks);
    rig
}

/// Interpreter frames per node in `rig.sent()`.
fn frames_per_drive(rig: &Rig) -> Vec<usize> {
    let mut counts = std::collections::BTreeMap::new();
    for frame in rig.sent() {
        if let Ok((node, _)) = Request::parse(frame) {
            *counts.entry(node.get()).or_insert(0) += 1;
        }
    }
    counts.into_values().collect()
}

/// Everything a streaming run must keep: operational, no drive-side trouble, at most two
/// interpreter frames per drive per cycle.
fn check_healthy(rig: &Rig) {
    assert!(
        rig.manager().is_operational(),
        "fault {:?}",
        rig.manager().fault()
    );
    assert!(frames_per_drive(rig).iter().all(|&n| n <= 2));
    for drive in rig.bus().drives() {
        let stats = drive.stats();
        assert_eq!(
            (stats.underflows, stats.overflows, stats.commands_lost),
            (0, 0, 0),
            "{:?}: {stats:?}",
            drive.node()
        );
    }
}

/// Runs 60 s of streaming with motion from `motion` (called every tick with the rig and the
/// time since the start); checks the stream all along and returns the leads seen.
fn stream_for_a_minute(
    rig: &mut Rig,
    extra_lag: usize,
    mut motion: impl FnMut(&mut Rig, f64),
) -> BTreeSet<u32> {
    let dof = rig.config.dof();
    let start = rig.now;
    let mut leads = BTreeSet::new();
    let mut worst_error: f64 = 0.0;
    let mut history: Vec<Joints> = Vec::new();
    while rig.now - start < 60.0 {
        motion(rig, rig.now - start);
        rig.tick();
        check_healthy(rig);
        leads.extend((0..dof).filter_map(|j| rig.manager().lead(j)));
        // The drives follow the commands a few periods late (two of buffering, one or two
        // of measurement age — a drive reading its read index skips its position — and a few
        // ms of servo lag): the measurement lies within the range of the commands of two to
        // six cycles ago (seven with `extra_lag`).
        history.push(rig.manager().commanded());
        let recent = history.iter().rev().skip(2).take(5 + extra_lag);
        if history.len() > 7 + extra_lag {
            let measured = rig.manager().measured();
            for j in 0..dof {
                let (lo, hi) = recent.clone().fold((f64::MAX, f64::MIN), |(lo, hi), c| {
                    (lo.min(c[j]), hi.max(c[j]))
                });
                let outside = (lo - measured[j]).max(measured[j] - hi).max(0.0);
                worst_error = worst_error.max(outside);
            }
        }
    }
    // A count or two (rounding, the cubic's overshoot, the lag's tail).
    assert!(worst_error < 1e-4, "worst tracking error {worst_error}");
    leads
}

#[test]
fn mk1_streams_a_minute_of_joint_and_cartesian_motion() {
    let mut rig = Rig::new(mk1_fast());
    let ticks = rig.start();
    assert!(ticks < 30, "start took {ticks} cycles");
    rig.ticks(3);
    // All drives began within a few frame times of each other (report the skew).
    let begun: Vec<u64> = rig
        .bus()
        .drives()
        .map(|d| d.stats().begun_at.unwrap())
        .collect();
    let skew = begun.iter().max().unwrap() - begun.iter().min().unwrap();
    println!("BG skew over 6 drives at 500 kbit/s: {} µs", skew / 1000);
    assert!(skew < 2_000_000);
    rig.bus_mut().reset_stats();
    rig.ctrl_mut().set_mode(Mode::Joint).unwrap();
    rig.ctrl_mut().move_joints(&MK1_READY, 0.0).unwrap();
    let mut shape_started = false;
    let leads = stream_for_a_minute(&mut rig, 0, |rig, t| {
        if !shape_started && !rig.ctrl().is_moving() && t > 1.0 {
            rig.ctrl_mut().set_mode(Mode::Cartesian).unwrap();
            let circle = Shape::Circle {
                radius: 0.1,
                period: 8.0,
                axis_i: 0,
                axis_j: 2,
            };
            rig.ctrl_mut().start_shape(circle).unwrap();
            shape_started = true;
        }
    });
    assert!(shape_started);
    assert_eq!(leads, BTreeSet::from([TARGET_LEAD]));
    let stats = rig.manager().stats();
    assert_eq!((stats.points_skipped, stats.points_inserted), (0, 0));
    // Every point reached at most two periods after it was written: it is fetched at the first
    // segment start after its write.
    for drive in rig.bus().drives() {
        let latency = drive.stats().latency;
        assert!(latency.points > 3000);
        let periods = latency.max_ns as f64 * 1e-9 / rig.period;
        assert!(periods <= 2.0, "{:?}: {periods} periods", drive.node());
    }
    // The stream moved the arm (a circle of 10 cm needs more than a few mrad).
    assert!(rig.manager().measured()[1] - 0.0 > 0.3);
}

#[test]
fn mk2_streams_a_minute_to_eight_drives() {
    let config = robot("ranger-mk2")
        .edit(|config| {
            for joint in config.joints.iter_mut() {
                joint.max_velocity = 0.4;
                joint.max_rate = 2.0;
                joint.drive.max_speed = 2.0;
            }
        })
        .unwrap();
    let mut rig = Rig::new(config);
    rig.start();
    rig.ctrl_mut().set_mode(Mode::Joint).unwrap();
    let goals = [
        [0.3, 0.4, -0.5, 0.6, -0.2, 0.3, 0.5, -0.4],
        [-0.2, -0.3, 0.4, -0.5, 0.3, -0.4, -0.2, 0.6],
        [0.0; 8],
    ];
    let mut next = 0;
    let leads = stream_for_a_minute(&mut rig, 0, |rig, _| {
        if !rig.ctrl().is_moving() {
            rig.ctrl_mut()
                .move_joints(&goals[next % goals.len()], 0.0)
                .unwrap();
            next += 1;
        }
    });
    assert!(next >= 6, "only {next} moves");
    assert_eq!(leads, BTreeSet::from([TARGET_LEAD]));
    assert_eq!(rig.bus().drives().count(), 8);
    assert!(rig.bus().drives().all(|d| d.pt_running()));
}

#[test]
fn stop_holds_the_last_command_and_start_resumes_without_a_jump() {
    let mut rig = moving(60);
    let accepted = rig.tick_accepted().unwrap();
    rig.manager_mut().stop().unwrap();
    assert_eq!(rig.manager_mut().stop(), Err(LifecycleError::NotRunning));
    rig.until(20, |r| r.manager().state() == DriveState::Stopped);
    assert_eq!(rig.manager().fault(), None);
    assert!(!rig.manager().is_operational());
    // The drives finished the queued points and hold the last command taken (to a count),
    // not some earlier point (the seed backtracked, spec §9 item 36).
    rig.ticks(10);
    assert!(rig.bus().drives().all(|d| !d.pt_running()));
    // `ST` found every drive's profile at rest on the hold point, past its second repeat (not
    // in the overshoot before it).
    for drive in rig.bus().drives() {
        let table = drive.table();
        let hold = f64::from(table.qp(table.read_index()).unwrap());
        assert!(
            (drive.profile() - hold).abs() < 1e-6,
            "{:?}: {} against {hold}",
            drive.node(),
            drive.profile()
        );
    }
    let held = rig.manager().commanded();
    for (a, h) in accepted.iter().zip(held.iter()) {
        assert!((a - h).abs() < 1e-5, "held {h}, last command {a}");
    }
    for (p, h) in rig.drive_positions().iter().zip(held.iter()) {
        assert!((p - h).abs() < 2e-5, "drive at {p}, held {h}");
    }
    // The controller keeps asking for motion; the stopped drives ignore it.
    rig.ticks(20);
    for (p, h) in rig.drive_positions().iter().zip(held.iter()) {
        assert!((p - h).abs() < 2e-5);
    }
    // ON again: the stream resumes where the arm is, nothing jumps.
    rig.ctrl_mut().stop(StopCause::Stop);
    rig.ctrl_mut().set_mode(Mode::Off).unwrap();
    let before = rig.drive_positions();
    rig.start();
    rig.ticks(30);
    for (a, b) in rig.drive_positions().iter().zip(&before) {
        assert!((a - b).abs() < 2e-5);
    }
    check_healthy(&rig);
}

#[test]
fn a_drive_in_another_unit_mode_is_switched_to_position_mode() {
    let mut rig = Rig::with(robot("ranger-mk1"), DriveSettings::default(), |bus| {
        let mut drive = bus.drive(103).unwrap().clone();
        assert_eq!(drive.nmt_state(), NmtState::PreOperational);
        drive.faults.stuck_unit_mode = false;
        *bus.drive_mut(103).unwrap() = speed_mode(drive);
    });
    let ticks = rig.start();
    // The change costs the 100 ms settle.
    assert!(ticks as f64 * rig.period > 0.1);
    rig.ticks(5);
    check_healthy(&rig);
}

/// The same drive, powered up in speed mode.
fn speed_mode(drive: armgate_core::sim::SimWhistle) -> armgate_core::sim::SimWhistle {
    let _ = drive;
    let config = robot("ranger-mk1");
    let mut whistle = armgate_core::sim::WhistleConfig::for_joint(&config.joints[2]).unwrap();
    whistle.unit_mode = 2;
    armgate_core::sim::SimWhistle::new(whistle)
}

#[test]
fn temperatures_are_unknown_until_heard_then_rise_with_effort() {
    let mut rig = Rig::new(mk1_fast());
    assert!(
        rig.manager()
            .temperatures()
            .iter()
            .all(|&t| t == UNKNOWN_TEMPERATURE)
    );
    assert_eq!(rig.manager().temperatures().len(), 6);
    rig.start();
    // Every drive reads its temperature once per 100 cycles.
    rig.ticks(110);
    let cold = rig.manager().temperatures();
    assert!(cold.iter().all(|&t| t == 25.0), "{cold:?}");
    rig.ctrl_mut().set_mode(Mode::Joint).unwrap();
    let far = [0.0, 1.5, -1.5, 2.0, 0.9, 2.0];
    for _ in 0..4 {
        rig.ctrl_mut().move_joints(&far, 0.0).unwrap();
        rig.until(3000, |r| !r.ctrl().is_moving());
        rig.ctrl_mut().move_joints(&MK1_READY, 0.0).unwrap();
        rig.until(3000, |r| !r.ctrl().is_moving());
    }
    rig.ticks(110);
    let warm = rig.manager().temperatures();
    assert!(warm.iter().zip(cold.iter()).any(|(w, c)| w > c), "{warm:?}");
}

#[test]
fn recalibration_moves_the_reading_not_the_arm() {
    let mut rig = Rig::new(mk1_fast());
    // Before any position is read, there is nothing to recalibrate.
    assert_eq!(
        rig.manager_mut().recalibrate(&MK1_READY),
        Err(Refusal::NotReady)
    );
    rig.start();
    rig.ticks(5);
    assert_eq!(
        rig.manager_mut().recalibrate(&MK1_READY[..5]),
        Err(Refusal::WrongJointCount)
    );
    let mut nan = MK1_READY;
    nan[2] = f64::NAN;
    assert_eq!(
        rig.manager_mut().recalibrate(&nan),
        Err(Refusal::InvalidNumber)
    );
    // Refused while commands stream.
    rig.ctrl_mut().set_mode(Mode::Joint).unwrap();
    rig.tick();
    assert_eq!(
        rig.manager_mut().recalibrate(&MK1_READY),
        Err(Refusal::Busy)
    );
    // In mode off (commands None) it is taken: the reading jumps, the drives stay.
    rig.ctrl_mut().set_mode(Mode::Off).unwrap();
    rig.tick();
    let counts: Vec<i32> = rig.bus().drives().map(|d| d.position()).collect();
    rig.manager_mut().recalibrate(&MK1_READY).unwrap();
    let measured = rig.manager().measured();
    for (m, r) in measured.iter().zip(MK1_READY) {
        assert!((m - r).abs() < 1e-12, "{m} vs {r}");
    }
    rig.ticks(20);
    let after: Vec<i32> = rig.bus().drives().map(|d| d.position()).collect();
    assert_eq!(after, counts);
    // A move from the new reading now moves the arm relative to it.
    rig.ctrl_mut().set_mode(Mode::Joint).unwrap();
    let mut goal = MK1_READY;
    goal[0] += 0.05;
    rig.ctrl_mut().move_joints(&goal, 0.0).unwrap();
    rig.until(2000, |r| !r.ctrl().is_moving());
    rig.ticks(10);
    assert!((rig.manager().measured()[0] - goal[0]).abs() < 1e-5);
    let moved = rig.bus().drives().next().unwrap().position() - counts[0];
    assert!((f64::from(moved) - 0.05 * 817_741.0 / std::f64::consts::TAU).abs() < 2.0);
}

#[test]
fn joints_without_a_drive_mirror_the_command() {
    // Every joint pretend (the hybrid robot): no bus traffic at all.
    let config = robot("hybrid");
    let mut rig = Rig::new(config.clone());
    rig.manager_mut().start().unwrap();
    assert!(rig.manager().is_operational());
    rig.tick();
    rig.ctrl_mut().set_mode(Mode::Joint).unwrap();
    let mut goal: Vec<f64> = rig.manager().measured().to_vec();
    goal[0] += 0.05;
    goal[3] -= 0.1;
    rig.ctrl_mut().move_joints(&goal, 0.0).unwrap();
    for _ in 0..400 {
        let out = rig.tick();
        assert!(rig.sent().is_empty());
        if let Some(command) = out.command {
            assert_eq!(rig.manager().measured(), command);
        }
    }
    assert!((rig.manager().measured()[0] - goal[0]).abs() < 1e-9);
    assert!(
        rig.manager()
            .temperatures()
            .iter()
            .all(|&t| t == UNKNOWN_TEMPERATURE)
    );
    rig.manager_mut().stop().unwrap();
    assert_eq!(rig.manager().state(), DriveState::Stopped);

    // A mixed arm: joint 3 without a drive mirrors, the others stream.
    let config = mk1_fast()
        .edit(|config| config.joints[2].drive.node_id = 0)
        .unwrap();
    let mut rig = Rig::new(config);
    assert_eq!(rig.manager().measured()[2], 1.5708); // home until commanded
    rig.start();
    assert_eq!(rig.bus().drives().count(), 5);
    rig.ctrl_mut().set_mode(Mode::Joint).unwrap();
    rig.ctrl_mut().move_joints(&MK1_READY, 0.0).unwrap();
    rig.until(3000, |r| !r.ctrl().is_moving());
    rig.ticks(10);
    check_healthy(&rig);
    assert_eq!(rig.manager().measured()[2], MK1_READY[2]);
    assert_eq!(rig.manager().temperatures()[2], UNKNOWN_TEMPERATURE);
    assert!((rig.manager().measured()[4] - MK1_READY[4]).abs() < 1e-5);
}

#[test]
fn drive_clocks_off_by_a_thousand_ppm_are_followed() {
    // A fast loop (8.64 ms) and clocks 0.1 % fast or slow: the segment boundaries slide a
    // full period every 1000 cycles, so a minute holds several slips per drive.
    let config = mk1_fast()
        .edit(|config| config.control_period = 24.0 * 360e-6)
        .unwrap();
    let mut rig = Rig::with(config.clone(), DriveSettings::default(), |bus| {
        let drives: Vec<_> = config
            .joints
            .iter()
            .enumerate()
            .map(|(i, joint)| {
                let mut whistle = armgate_core::sim::WhistleConfig::for_joint(joint).unwrap();
                whistle.clock_error_ppm = if i % 2 == 0 { 1000.0 } else { -1000.0 };
                armgate_core::sim::SimWhistle::new(whistle)
            })
            .collect();
        *bus = armgate_core::sim::VirtualBus::new(500_000, drives);
    });
    rig.start();
    rig.ctrl_mut().set_mode(Mode::Joint).unwrap();
    let goals = [MK1_READY, [1.0, 0.2, 0.3, -0.5, 1.2, 0.8]];
    let mut next = 0;
    rig.bus_mut().reset_stats();
    // A lead of 3 while a slip passes delays the motion one more period.
    let leads = stream_for_a_minute(&mut rig, 1, |rig, _| {
        if !rig.ctrl().is_moving() {
            rig.ctrl_mut().move_joints(&goals[next % 2], 0.0).unwrap();
            next += 1;
        }
    });
    let stats = rig.manager().stats();
    println!("clock drift: {stats:?}, leads {leads:?}");
    // Fast drives needed points inserted, slow ones points skipped.
    assert!(
        stats.points_inserted >= 3 && stats.points_skipped >= 3,
        "{stats:?}"
    );
    assert!(leads.iter().all(|l| (1..=3).contains(l)));
    for drive in rig.bus().drives() {
        let periods = drive.stats().latency.max_ns as f64 * 1e-9 / rig.period;
        assert!(periods <= 3.0, "{:?}: {periods}", drive.node());
    }
}

#[test]
fn drives_stop_by_themselves_when_the_controller_dies() {
    let mut rig = moving(50);
    assert!(rig.bus().drives().all(|d| d.pt_running()));
    // The controller stops: no more points, no more heartbeats. The drives underflow first
    // (within two segments), then miss the heartbeat (300 ms after the last, which went out
    // at most 100 ms before) and go pre-operational.
    let died = rig.now;
    rig.bus_mut().advance(died + 0.1).unwrap();
    assert!(rig.bus().drives().all(|d| !d.pt_running()));
    assert!(
        rig.bus()
            .drives()
            .all(|d| d.nmt_state() == NmtState::Operational)
    );
    rig.bus_mut().advance(died + 0.45).unwrap();
    for drive in rig.bus().drives() {
        assert_eq!(drive.nmt_state(), NmtState::PreOperational);
        assert_eq!(drive.stats().heartbeat_timeouts, 1);
    }
    // A controller that comes back (its shell 0.45 s late: the cycle catches up, the first
    // tick at once) sees the drives' emergencies.
    let back = ((died + 0.45) * 1e6) as u64;
    rig.tick_at(back);
    assert!(matches!(
        rig.manager().fault(),
        Some(DriveFault::Underflow { .. } | DriveFault::HeartbeatLost { .. })
    ));
    assert!(!rig.manager().is_operational());
    // The rest of the catch-up runs back to back.
    while rig.cycle.next_due_us() <= back {
        rig.tick_at(back);
    }
    // ON brings everything back (NMT start first).
    rig.until(20, |r| r.manager().state() == DriveState::Faulted);
    rig.ctrl_mut().stop(StopCause::Stop);
    rig.ctrl_mut().set_mode(Mode::Off).unwrap();
    rig.start();
    rig.bus_mut().reset_stats();
    rig.ticks(20);
    check_healthy(&rig);
}

/// `OF` (the manager's `stop()`) removes no power: the drives end their PT motion and hold
/// the last command under servo, motors on (docs/safety.md: a category-2 stop).
#[test]
fn stopped_drives_keep_their_motors_on() {
    use armgate_protocol::can::interpreter::{Index, Mnemonic, Reply, Value};
    use drives_rig::frames::{exchange, query};
    let mut rig = moving(60);
    rig.manager_mut().stop().unwrap();
    rig.until(20, |r| r.manager().state() == DriveState::Stopped);
    rig.ticks(10);
    let nodes: Vec<u8> = rig.bus().drives().map(|d| d.node().get()).collect();
    for node in nodes {
        let answers = exchange(rig.bus_mut(), &[query(node, Mnemonic::MO, 0)], 0.01);
        let motor = answers.iter().map(|f| Reply::parse(f).unwrap().1);
        let on = Reply::Value {
            command: Mnemonic::MO,
            index: Index::ZERO,
            value: Value::Int(1),
        };
        assert!(
            motor.into_iter().any(|r| r == on),
            "node {node}: {answers:?}"
        );
    }
}

/// The reply to a client request of `command` with index `index`, handled by the next tick.
fn ask(rig: &mut Rig, command: armgate_protocol::client::Command, index: u8) -> Vec<u8> {
    let bytes = armgate_protocol::client::Request {
        command,
        values: [0.0; 7],
        index,
    }
    .to_bytes();
    rig.client
        .requests
        .push_back(armgate_core::cycle::Datagram::new(&bytes, ()));
    rig.client.replies.clear();
    rig.tick();
    rig.client.replies[0].payload().to_vec()
}

/// f0 of a 31-byte reply.
fn f0(reply: &[u8]) -> f32 {
    f32::from_le_bytes(reply[2..6].try_into().unwrap())
}

/// A CAN bus-off while the arm moves (docs/safety.md, "Faults, power loss and the network"):
/// the client gets `ER35 CAN bus off`; nothing reaches the drives, which end their PT motion
/// for lack of points and go pre-operational once the controller's heartbeat is missed (as
/// when the controller dies); motion is refused; when the bus comes back nothing moves until
/// the client's `ON`, and the interrupted move does not resume after it either.
#[test]
fn a_bus_off_at_speed_stops_the_drives_and_nothing_moves_until_on() {
    use armgate_protocol::client::Command;
    let mut rig = moving(50);
    // The client that will get the notice (the last to send a valid request).
    assert_eq!(&ask(&mut rig, Command::Status, 0)[..2], b"QS");
    assert!(rig.bus().drives().all(|d| d.pt_running()));
    let before = rig.drive_positions();
    rig.tick();
    let speed = rig
        .drive_positions()
        .iter()
        .zip(&before)
        .map(|(a, b)| (a - b).abs() / rig.period)
        .fold(0.0, f64::max);
    assert!(speed > 0.1, "moving at {speed} rad/s");
    rig.bus_mut().set_bus_off(true);
    let off = rig.now;
    let (mut pt_ended, mut pre_operational) = (None, None);
    let mut positions = vec![before, rig.drive_positions()];
    for _ in 0..40 {
        rig.tick();
        positions.push(rig.drive_positions());
        if pt_ended.is_none() && rig.bus().drives().all(|d| !d.pt_running()) {
            pt_ended = Some(rig.now - off);
        }
        if rig
            .bus()
            .drives()
            .all(|d| d.nmt_state() == NmtState::PreOperational)
        {
            pre_operational = Some(rig.now - off);
            break;
        }
    }
    let (pt_ended, pre_operational) = (pt_ended.unwrap(), pre_operational.unwrap());
    // The largest change of a drive's speed from one period to the next, and the way run
    // after the bus-off (the drives' own stop: not shaped by the controller).
    let dt = rig.period;
    let deceleration = positions
        .windows(3)
        .flat_map(|w| (0..w[0].len()).map(move |j| (w[2][j] - 2.0 * w[1][j] + w[0][j]).abs()))
        .fold(0.0, f64::max)
        / (dt * dt);
    let run_on = (0..positions[1].len())
        .map(|j| (positions[positions.len() - 1][j] - positions[1][j]).abs())
        .fold(0.0, f64::max);
    let notices: Vec<String> = rig
        .client
        .notices
        .iter()
        .map(|n| {
            String::from_utf8_lossy(n.payload())
                .trim_end_matches('\0')
                .to_string()
        })
        .collect();
    // SQ 0: drives faulted (f1 4) with code 35 (f2), the arm holding (f4 0); SQ 2: no stop
    // cause (0): the supervisor did not stop the arm, the drives did.
    let cause = f0(&ask(&mut rig, Command::Status, 2));
    let status = ask(&mut rig, Command::Status, 0);
    let field = |k: usize| f32::from_le_bytes(status[2 + 4 * k..6 + 4 * k].try_into().unwrap());
    let (drives, code, motion) = (field(1), field(2), field(4));
    eprintln!(
        "bus-off at {:.2} rad/s (simulated): PT motion ended {:.0} ms later after {:.1} mrad, \
         peak deceleration {deceleration:.1} rad/s², every drive \
         pre-operational {:.0} ms later; notices {notices:?}; SQ 0 drives {drives} code {code} \
         motion {motion}; SQ 2 cause {cause}",
        speed,
        pt_ended * 1e3,
        run_on * 1e3,
        pre_operational * 1e3
    );
    assert_eq!(
        rig.manager().fault(),
        Some(DriveFault::Bus(armgate_core::drives::BusFault::BusOff))
    );
    assert!(
        notices.iter().any(|n| n.starts_with("ER35 CAN bus off")),
        "{notices:?}"
    );
    assert_eq!((drives, code, motion, cause), (4.0, 35.0, 0.0, 0.0));
    assert!(pt_ended <= 0.1, "PT ran {pt_ended} s");
    assert!(
        pre_operational <= 0.45,
        "pre-operational after {pre_operational} s"
    );
    for drive in rig.bus().drives() {
        assert_eq!(drive.stats().heartbeat_timeouts, 1);
    }
    // Motion is refused while the fault stands.
    let refusal = ask(&mut rig, Command::JointBegin, 0);
    assert!(
        refusal.starts_with(b"ER20"),
        "{}",
        String::from_utf8_lossy(&refusal)
    );
    // The bus comes back: nothing moves on its own, the fault stays latched.
    rig.bus_mut().set_bus_off(false);
    let rest = rig.drive_positions();
    rig.ticks(100);
    assert_eq!(rig.drive_positions(), rest);
    assert!(rig.bus().drives().all(|d| !d.pt_running()));
    assert_eq!(rig.manager().state(), DriveState::Faulted);
    // ON restarts the drives; the arm holds where it stopped (the move does not resume).
    assert_eq!(&ask(&mut rig, Command::On, 0)[..2], b"NO");
    rig.until(200, |r| r.manager().is_operational());
    rig.ticks(50);
    for (now, then) in rig.drive_positions().iter().zip(&rest) {
        assert!((now - then).abs() < 1e-4, "moved from {then} to {now}");
    }
    assert_eq!(
        rig.ctrl().motion(),
        armgate_protocol::client::Motion::Holding
    );
}
