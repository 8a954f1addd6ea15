//! Twist and joint-rate streaming (`TW`, `jW`) through the whole cycle: datagrams in, the
//! set-points the drives get out (docs/motion.md, "Twist and joint-velocity streaming").
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]
// The seed deployed rounded angles such as 1.5708.
#![allow(clippy::approx_constant)]

mod common;

use armgate_core::config::ValidRobot;
use armgate_core::cycle::{Cycle, Datagram, Dropped, Link, Outgoing};
use armgate_core::kinematics::{Chain, Joints};
use armgate_core::math::{self, Frame, Vector3};
use armgate_core::motion::{MARGIN_SHARE, Mode, TIMEOUT_PERIODS};
use armgate_core::sim::{ArmModel, IdealArm, SimulatedDrives};
use armgate_protocol::client::{
    Command, Hold, JointRates, Message, Motion, Notice, Request, Text, Twist, TwistFrame, VALUES,
};

/// No datagrams through the link: the tests answer requests between ticks, which is where the
/// cycle handles them (after the control step).
struct Silent;

impl Link<()> for Silent {
    fn receive(&mut self) -> Option<Datagram<()>> {
        None
    }
    fn send(&mut self, _: &Datagram<()>, _: Outgoing) -> Result<(), Dropped> {
        Ok(())
    }
}

/// The cycle on an ideal simulated arm, keeping every tick's joint set-point.
struct Stream {
    cycle: Cycle<SimulatedDrives, ()>,
    config: ValidRobot,
    chain: Chain,
    setpoints: Vec<Joints>,
    /// Every tick's hold, as the warning relay sees it.
    holds: Vec<Option<Hold>>,
}

impl Stream {
    fn new(config: ValidRobot, q0: &[f64], mode: Mode) -> Self {
        let arm = IdealArm::new(Joints::from_slice(q0).unwrap());
        let mut stream = Self {
            cycle: Cycle::new(&config, SimulatedDrives::new(ArmModel::Ideal(arm))),
            chain: Chain::new(&config),
            config,
            setpoints: Vec::new(),
            holds: Vec::new(),
        };
        stream.tick();
        let mut values = [0.0; VALUES];
        values[0] = f32::from(mode.value());
        stream.ok(Request {
            command: Command::ChangeMode,
            values,
            index: 0,
        });
        stream.tick();
        stream
    }

    fn tick(&mut self) {
        let due = self.cycle.next_due_us();
        let out = self.cycle.tick(due, &mut Silent).step.unwrap();
        self.holds.push(out.events.hold);
        if let Some(q) = out.command {
            self.setpoints.push(q);
        }
    }

    /// Sends a request that must be answered with the reversed characters.
    fn ok(&mut self, request: Request) -> [u8; 31] {
        let reply = self.cycle.answer(&request.to_bytes(), ());
        assert_eq!(
            reply[..2],
            request.command.reply_chars(),
            "{:?}",
            text(&reply)
        );
        reply
    }

    fn twist(&mut self, linear: [f64; 3], angular: [f64; 3], frame: TwistFrame) {
        self.ok(Twist {
            linear: linear.map(|v| v as f32),
            angular: angular.map(|v| v as f32),
            frame,
        }
        .to_request());
    }

    fn joint_rates(&mut self, rates: &[f64]) {
        let mut bank = |bank_2: bool, values: &[f64]| {
            let mut r = [0.0f32; 6];
            for (r, v) in r.iter_mut().zip(values) {
                *r = *v as f32;
            }
            self.ok(JointRates { bank_2, rates: r }.to_request());
        };
        if rates.len() > 6 {
            bank(true, &rates[6..]);
        }
        bank(false, &rates[..rates.len().min(6)]);
    }

    fn last(&self) -> Joints {
        *self.setpoints.last().unwrap()
    }

    fn pose(&self) -> Frame {
        self.chain.forward(&self.last()).unwrap()
    }

    fn period(&self) -> f64 {
        self.config.control_period
    }

    fn motion(&self) -> Motion {
        self.cycle.handler().controller().motion()
    }

    /// Every joint's per-tick velocity and acceleration stay within the limits (relative
    /// 1e-9): speed ≤ max_rate, acceleration ≤ max_acceleration.
    fn assert_within_limits(&self) {
        let t = self.period();
        for (k, w) in self.setpoints.windows(3).enumerate() {
            for (i, joint) in self.config.joints.iter().enumerate() {
                let v1 = (w[1][i] - w[0][i]) / t;
                let v2 = (w[2][i] - w[1][i]) / t;
                assert!(
                    v2.abs() <= joint.max_rate * (1.0 + 1e-9),
                    "tick {k} joint {i}: {v2} rad/s"
                );
                let a = (v2 - v1) / t;
                assert!(
                    a.abs() <= joint.max_acceleration * (1.0 + 1e-9),
                    "tick {k} joint {i}: {a} rad/s²"
                );
            }
        }
    }
}

fn text(reply: &[u8; 31]) -> Option<String> {
    let message = Message::new_checked(&reply[..]).ok()?;
    Text::parse(&message).ok().map(|t| t.as_str().to_owned())
}

/// A request without values, index 0.
fn bare(command: Command) -> Request {
    Request {
        command,
        values: [0.0; VALUES],
        index: 0,
    }
}

const MK1_READY: [f64; 6] = [1.5708, 0.6, -0.4, 0.2, 1.8, 0.1];

fn mk1(mode: Mode) -> Stream {
    Stream::new(common::robot("ranger-mk1"), &MK1_READY, mode)
}

#[test]
fn a_twist_changes_the_very_next_setpoint() {
    let mut s = mk1(Mode::Cartesian);
    s.tick();
    let before = s.last();
    s.twist([0.01, 0.0, 0.0], [0.0; 3], TwistFrame::Base);
    s.tick();
    assert_ne!(s.last(), before, "latency over one period");
    assert_eq!(s.motion(), Motion::Streaming);

    let mut s = mk1(Mode::Joint);
    s.tick();
    let before = s.last();
    s.joint_rates(&[0.0, 0.0, 0.05, 0.0, 0.0, 0.0]);
    s.tick();
    let after = s.last();
    assert!(after[2] > before[2], "latency over one period");
    assert_eq!(after[..2], before[..2]);
}

#[test]
fn a_silent_client_stops_within_the_timeout_and_a_ramp_within_the_limits() {
    let mut s = mk1(Mode::Cartesian);
    for _ in 0..150 {
        s.twist([0.0, 0.0, 0.015], [0.0; 3], TwistFrame::Base);
        s.tick();
    }
    let streaming = s.setpoints.len();
    let speed = |s: &Stream, k: usize| {
        let p = |k: usize| s.chain.forward(&s.setpoints[k]).unwrap().translation.vector;
        (p(k) - p(k - 1)).norm() / s.period()
    };
    // Joint rates from the Jacobian at the start of each step: first order, 0.1 %.
    assert!((speed(&s, streaming - 1) - 0.015).abs() < 1.5e-5);
    // The ramp from the fastest joint's speed at its acceleration limit.
    let t = s.period();
    let ramp = s
        .cycle
        .handler()
        .controller()
        .stream()
        .velocity()
        .iter()
        .zip(&s.config.joints)
        .map(|(v, j)| (v.abs() / (j.max_acceleration * t)).ceil() as usize)
        .max()
        .unwrap();
    for _ in 0..(TIMEOUT_PERIODS as usize + ramp + 5) {
        s.tick();
    }
    // Full speed for the timeout (the last twist's first tick was the loop's last), then a
    // ramp, then rest.
    for k in 0..TIMEOUT_PERIODS as usize - 1 {
        assert!(
            (speed(&s, streaming + k) - 0.015).abs() < 1.5e-5,
            "tick {k}"
        );
    }
    let rest = (streaming..s.setpoints.len())
        .find(|k| s.setpoints[*k] == s.setpoints[k - 1])
        .unwrap();
    // Ticks from the last twist (just before set-point `streaming - 1`) to the first at rest.
    let stopped_after = rest - (streaming - 1);
    println!(
        "silent client: at rest {stopped_after} ticks after the last twist (timeout {TIMEOUT_PERIODS} + ramp {ramp})"
    );
    assert!(stopped_after <= TIMEOUT_PERIODS as usize + ramp);
    assert!(s.setpoints[rest..].iter().all(|q| *q == s.last()));
    assert_eq!(s.motion(), Motion::Holding);
    s.assert_within_limits();
}

#[test]
fn a_jog_through_the_wrist_singularity_neither_stops_nor_exceeds_a_rate_limit() {
    // ranger-mk1's wrist is singular at q5 = π (axes 4 and 6 aligned). The jog starts 0.1 rad
    // short of it and runs straight along the direction that turns q5 fastest (the linear
    // part of row 5 of J⁻¹), keeping the orientation.
    let config = common::robot("ranger-mk1");
    let chain = Chain::new(&config);
    let mut q0 = MK1_READY;
    q0[4] = core::f64::consts::PI - 0.1;
    let start = chain.forward(&q0).unwrap();
    let j = chain
        .jacobian(&q0)
        .unwrap()
        .fixed_view::<6, 6>(0, 0)
        .into_owned();
    let inverse = j.try_inverse().unwrap();
    let direction = Vector3::new(inverse[(4, 0)], inverse[(4, 1)], inverse[(4, 2)]).normalize();
    let (speed, half) = (0.015, 0.04);
    let mut s = Stream::new(config, &q0, Mode::Cartesian);
    // Up to three times the time the line takes at full speed.
    let ticks = (6.0 * half / speed / s.period()) as usize;
    let mut travelled = 0.0;
    let (mut deviation, mut tilt, mut slowest) = (0.0f64, 0.0f64, f64::INFINITY);
    let mut nearest = f64::INFINITY;
    let v = direction * speed;
    for k in 0..ticks {
        if travelled >= 2.0 * half {
            break;
        }
        s.twist([v.x, v.y, v.z], [0.0; 3], TwistFrame::Base);
        s.tick();
        let pose = s.pose();
        let offset = pose.translation.vector - start.translation.vector;
        deviation = deviation.max((offset - direction * offset.dot(&direction)).norm());
        tilt = tilt.max(math::diff(&start, &pose).fixed_rows::<3>(3).norm());
        nearest = nearest.min((s.last()[4] - core::f64::consts::PI).abs());
        // After the ramp-up: the tool keeps moving along the line.
        if k > 10 {
            let previous = chain.forward(&s.setpoints[s.setpoints.len() - 2]).unwrap();
            let step = (pose.translation.vector - previous.translation.vector).dot(&direction);
            slowest = slowest.min(step / s.period());
        }
        travelled = offset.dot(&direction);
    }
    let tilt_at_end = math::diff(&start, &s.pose()).fixed_rows::<3>(3).norm();
    // Then on along the same line for 4 s more: the path reference wins the orientation back.
    for _ in 0..(4.0 / s.period()) as usize {
        s.twist([v.x, v.y, v.z], [0.0; 3], TwistFrame::Base);
        s.tick();
    }
    let tilt_after = math::diff(&start, &s.pose()).fixed_rows::<3>(3).norm();
    println!(
        "wrist-singularity jog (ranger-mk1, {speed} m/s, {:.0} mm): travelled {:.1} mm, \
         slowest {:.1} mm/s, closest |q5 − π| {nearest:.4} rad, path deviation {:.3} mm, \
         orientation deviation {:.3}° (at the end of the line {:.3}°, 60 mm further on {:.4}°)",
        2e3 * half,
        travelled * 1e3,
        slowest * 1e3,
        deviation * 1e3,
        tilt.to_degrees(),
        tilt_at_end.to_degrees(),
        tilt_after.to_degrees()
    );
    assert!(tilt_after < 0.5 * tilt_at_end, "{tilt_after}");
    s.assert_within_limits();
    assert!(slowest > 0.2 * speed, "stopped near the singularity");
    assert!(
        s.last()[4] > core::f64::consts::PI,
        "passed the singularity"
    );
    assert!(travelled >= 2.0 * half);
    // The damping gives way in orientation, not along the path.
    assert!(deviation < 0.0005, "{deviation}");
    assert!(tilt < 5f64.to_radians(), "{tilt}");
}

#[test]
fn a_joint_slows_down_before_its_limit_and_stops_at_the_margin() {
    // ranger-mk1's wrist pitch (joint 5) has its lower limit at 0.785 rad.
    let config = common::robot("ranger-mk1");
    let j5 = config.joints[4].clone();
    let bound = j5.min + MARGIN_SHARE * (j5.max - j5.min);
    let mut q0 = MK1_READY;
    q0[4] = bound + 0.05;
    let mut s = Stream::new(config, &q0, Mode::Joint);
    for _ in 0..200 {
        s.joint_rates(&[0.0, 0.0, 0.0, 0.0, -0.1, 0.0]);
        s.tick();
    }
    // Held at the margin from some tick on, naming the joint and its limit (the relay tells
    // the client once: `WN12 j5 at limit 0.785`); SQ 2 says so too.
    let held = s
        .holds
        .iter()
        .position(Option::is_some)
        .expect("never held");
    let text = Notice::Held(s.holds[held].unwrap()).text();
    assert_eq!(text.as_str(), "WN12 j5 at limit 0.785");
    assert!(s.holds[held..].iter().all(|h| *h == s.holds[held]));
    let cause = s.ok(Request {
        command: Command::Status,
        values: [0.0; VALUES],
        index: 2,
    });
    let cause = Message::new_checked(&cause[..]).unwrap();
    assert_eq!(cause.values()[..2], [7.0, 5.0]);
    let q5: Vec<f64> = s.setpoints.iter().map(|q| q[4]).collect();
    let t = s.period();
    let speeds: Vec<f64> = q5.windows(2).map(|w| (w[1] - w[0]) / t).collect();
    let fastest = speeds.iter().copied().fold(0.0, f64::min);
    println!(
        "joint-limit slow-down: fastest {fastest:.3} rad/s, stopped at {:.5} rad (margin bound \
         {bound:.5}, limit {})",
        s.last()[4],
        j5.min
    );
    assert!((fastest + 0.1).abs() < 1e-9, "reached the commanded rate");
    assert!(s.last()[4] >= bound - 1e-12, "{}", s.last()[4]);
    assert!(
        s.last()[4] < bound + 0.002,
        "stopped short: {}",
        s.last()[4]
    );
    assert_eq!(speeds.last().copied(), Some(0.0));
    // It slowed down over several ticks rather than stopping in one.
    let slowing = speeds
        .iter()
        .filter(|v| **v < -1e-6 && **v > -0.1 + 1e-9)
        .count();
    assert!(slowing >= 5, "{slowing}");
    s.assert_within_limits();
}

#[test]
fn a_redundant_arm_pulls_towards_mid_range_while_the_tool_follows_the_twist() {
    let config = common::robot("iiwa14");
    let q0 = [0.3, 0.6, 1.2, -1.2, 0.4, 0.8, 0.2];
    let mut s = Stream::new(config, &q0, Mode::Cartesian);
    let start = s.pose();
    let offset = |q: &Joints| q.iter().map(|v| v * v).sum::<f64>().sqrt();
    let before = offset(&s.last());
    let (v, ticks) = (0.05, 400);
    for _ in 0..ticks {
        s.twist([0.0, 0.0, v], [0.0; 3], TwistFrame::Base);
        s.tick();
    }
    let moved = s.pose().translation.vector - start.translation.vector;
    let along = moved.z;
    let aside = moved.xy().norm();
    let tilt = math::diff(&start, &s.pose()).fixed_rows::<3>(3).norm();
    let after = offset(&s.last());
    println!(
        "iiwa14 null space: |q − mid| {before:.3} → {after:.3} rad over {:.1} mm up, {:.4} mm \
         aside, {:.4}° tilt",
        along * 1e3,
        aside * 1e3,
        tilt.to_degrees()
    );
    assert!(after < before - 0.05, "{before} → {after}");
    // The pull stays in the null space: the tool goes where the twist says.
    assert!(along > 0.95 * v * s.period() * ticks as f64);
    assert!(aside < 1e-4 && tilt < 1e-4, "{aside} {tilt}");
    // A zero twist, streamed, holds the arm: no null-space motion without a motion asked for
    // (once the ramp to rest is over).
    for _ in 0..100 {
        s.twist([0.0; 3], [0.0; 3], TwistFrame::Base);
        s.tick();
    }
    let held = s.last();
    for _ in 0..200 {
        s.twist([0.0; 3], [0.0; 3], TwistFrame::Base);
        s.tick();
    }
    let drift = held
        .iter()
        .zip(s.last().iter())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(drift < 1e-6, "{drift}");
    s.assert_within_limits();
}

#[test]
fn streams_are_refused_in_the_wrong_mode_and_during_a_move() {
    let mut s = mk1(Mode::Joint);
    let reply = s.cycle.answer(
        &Twist {
            linear: [0.01, 0.0, 0.0],
            angular: [0.0; 3],
            frame: TwistFrame::Base,
        }
        .to_request()
        .to_bytes(),
        (),
    );
    assert_eq!(text(&reply).unwrap(), "ER20 Cmd TW needs mode 2");
    let mut tool = Twist {
        linear: [0.01, 0.0, 0.0],
        angular: [0.0; 3],
        frame: TwistFrame::Tool,
    }
    .to_request();
    tool.index = 0x81;
    assert_eq!(
        text(&s.cycle.answer(&tool.to_bytes(), ())).unwrap(),
        "ER24 Cmd TW bad index"
    );
    let mut nan = JointRates {
        bank_2: false,
        rates: [0.0; 6],
    };
    nan.rates[1] = f32::NAN;
    assert_eq!(
        text(&s.cycle.answer(&nan.to_request().to_bytes(), ())).unwrap(),
        "ER23 Cmd jW bad number"
    );
    // A bank 2 on a six-joint arm has no joints to carry.
    let upper = JointRates {
        bank_2: true,
        rates: [0.0; 6],
    };
    assert_eq!(
        text(&s.cycle.answer(&upper.to_request().to_bytes(), ())).unwrap(),
        "ER24 Cmd jW bad index"
    );
    // The echo: the rates as sent.
    let rates = JointRates {
        bank_2: false,
        rates: [0.0, 0.0, 0.05, 0.0, 0.0, 0.0],
    };
    let reply = s.ok(rates.to_request());
    let mut expected = rates.to_request().to_bytes();
    expected[..2].copy_from_slice(b"Wj");
    // f6: the three periods the rates hold.
    let timeout = (3.0 * s.period()) as f32;
    expected[26..30].copy_from_slice(&timeout.to_le_bytes());
    assert_eq!(reply, expected);
    s.tick();
    // jB during the stream is busy; ST ramps it to rest.
    s.ok(Request {
        command: Command::JointGoal,
        values: [1.5708, 0.6, -0.4, 0.2, 1.8, 0.1, 0.0],
        index: 0,
    });
    let busy = s.cycle.answer(&bare(Command::JointBegin).to_bytes(), ());
    assert!(
        text(&busy).unwrap().starts_with("ER20 Cmd jB"),
        "{:?}",
        text(&busy)
    );
    s.ok(bare(Command::Stop));
    for _ in 0..20 {
        s.tick();
    }
    assert_eq!(s.motion(), Motion::Holding);
    s.assert_within_limits();
}

#[test]
fn a_jog_towards_an_exclusion_box_ramps_to_rest_before_it() {
    // A box 30 mm ahead of the tool along x, 0.2 m wide.
    let config = common::robot("ranger-mk1");
    let p = Chain::new(&config)
        .forward(&MK1_READY)
        .unwrap()
        .translation
        .vector;
    let face = p.x + 0.03;
    let config = config
        .edit(|c| {
            c.workspace
                .boxes
                .push([face, face + 0.2, p.y - 0.1, p.y + 0.1, p.z - 0.1, p.z + 0.1])
                .unwrap();
            // The tool point's own hold; with the body on, the stream holds 21.9 mm before the
            // box, where the rest of the arm would come to rest in it (core/tests/body.rs).
            c.collision.enabled = false;
        })
        .unwrap();
    let mut s = Stream::new(config, &MK1_READY, Mode::Cartesian);
    for _ in 0..300 {
        s.twist([0.015, 0.0, 0.0], [0.0; 3], TwistFrame::Base);
        s.tick();
        assert!(s.pose().translation.vector.x <= face, "entered the box");
    }
    let gap = face - s.pose().translation.vector.x;
    println!(
        "towards an exclusion box at 15 mm/s: at rest {:.2} mm before it",
        gap * 1e3
    );
    assert!(gap < 0.002, "{gap}");
    let n = s.setpoints.len();
    assert_eq!(s.setpoints[n - 1], s.setpoints[n - 2], "at rest");
    s.assert_within_limits();
}

#[test]
fn a_change_of_direction_rounds_the_corner_and_returns_to_the_new_line() {
    let mut s = mk1(Mode::Cartesian);
    for _ in 0..(1.0 / s.period()) as usize {
        s.twist([0.015, 0.0, 0.0], [0.0; 3], TwistFrame::Base);
        s.tick();
    }
    let corner = s.pose().translation.vector;
    let mut overshoot = 0.0f64;
    for _ in 0..(2.0 / s.period()) as usize {
        s.twist([0.0, 0.015, 0.0], [0.0; 3], TwistFrame::Base);
        s.tick();
        overshoot = overshoot.max(s.pose().translation.vector.x - corner.x);
    }
    let end = s.pose().translation.vector;
    println!(
        "corner at 15 mm/s: {:.3} mm past the corner, back to the new line within {:.4} mm, \
         {:.1} mm along it",
        overshoot * 1e3,
        (end.x - corner.x).abs() * 1e3,
        (end.y - corner.y) * 1e3
    );
    assert!(overshoot < 0.001, "{overshoot}");
    assert!((end.x - corner.x).abs() < 2e-5);
    assert!((end.z - corner.z).abs() < 1e-5);
    s.assert_within_limits();
}

#[test]
fn eight_joint_rates_come_in_two_banks() {
    let config = common::robot("ranger-mk2");
    let q0 = [
        0.1508, -0.5897, 0.3452, -1.9859, -0.3564, 0.2665, 0.6688, 0.4256,
    ];
    let mut s = Stream::new(config, &q0, Mode::Joint);
    for _ in 0..20 {
        // Bank 2 (joints 7, 8) first, then bank 1 completes the vector.
        s.joint_rates(&[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.02]);
        s.tick();
    }
    let q = s.last();
    assert!(q[7] > q0[7] + 0.001, "joint 8 moved: {q:?}");
    assert!(q[..7].iter().zip(&q0).all(|(a, b)| (a - b).abs() < 1e-12));
    s.assert_within_limits();
}
