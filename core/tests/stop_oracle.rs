//! The supervisor's oracle: on every tick of seeded random request sequences, the commanded
//! joint acceleration is within `max_acceleration` (+1e-9 relative), every tick of a stop along
//! a Cartesian path changes each axis's set-point velocity within its Cartesian
//! `max_acceleration` (+1e-6 relative), the tool never gets strictly inside an exclusion box it
//! was not already in, and after a stop (`ST`, `OF`, a following error, a stream's own
//! timeout) no stream starts until a move or a zero stream re-arms it (issue 33). Among the requests, the arm is now and then
//! held where it is for a while (a blocked drive): the following-error stop it causes (stop
//! cause 9) is held to the same limits. The whole arm (issue 35): no commanded pose, in motion
//! or braking, brings a link into a box or another link, or the tool's capsule out of the
//! bounds, that was not in contact at the pose before ([`BodyOracle`]).
#![allow(
    clippy::approx_constant,
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod common;

use armgate_core::config::ValidRobot;
use armgate_core::kinematics::Joints;
use armgate_core::math::{self, Frame, Twist, Vector3};
use armgate_core::motion::{Controller, Mode, Refusal, StopCause};
use armgate_core::rng::SplitMix64;
use armgate_core::sim::{BodyOracle, IdealArm};
use armgate_protocol::client::Motion;
use armgate_protocol::client::TwistFrame;

/// Checks every tick's command against the previous two.
struct Oracle {
    config: ValidRobot,
    last: Vec<Joints>,
    /// The last two Cartesian set-points.
    setpoints: Vec<Frame>,
    inside: Vec<bool>,
    ticks: usize,
    /// Every link against the boxes, the bounds and the other links.
    body: BodyOracle,
}

impl Oracle {
    fn boxes_holding(&self, p: &Vector3<f64>) -> Vec<bool> {
        self.config
            .workspace
            .boxes
            .iter()
            .map(|&[x0, x1, y0, y1, z0, z1]| {
                x0 < p.x && p.x < x1 && y0 < p.y && p.y < y1 && z0 < p.z && p.z < z1
            })
            .collect()
    }

    /// A tick's Cartesian set-point; `stopping`: a stop was under way when the tick began.
    fn check_setpoint(&mut self, stopping: bool, setpoint: Option<Frame>) {
        let Some(sp) = setpoint else {
            self.setpoints.clear();
            return;
        };
        if let ([a, b], true) = (&self.setpoints[..], stopping) {
            let dt = self.config.control_period;
            let (v0, v1) = (math::diff(a, b), math::diff(b, &sp));
            for k in 0..6 {
                let acc = (v1[k] - v0[k]) / (dt * dt);
                let limit = self.config.cartesian.max_acceleration[k];
                assert!(
                    acc.abs() <= limit * (1.0 + 1e-6),
                    "tick {}: Cartesian axis {k} at {acc} (limit {limit}) in a stop",
                    self.ticks
                );
            }
        }
        self.setpoints.push(sp);
        if self.setpoints.len() > 2 {
            self.setpoints.remove(0);
        }
    }

    fn check(&mut self, ctrl: &Controller, command: Option<Joints>) {
        self.ticks += 1;
        let Some(q) = command else {
            self.last.clear();
            return;
        };
        let dt = self.config.control_period;
        if let [a, b] = self.last[..] {
            for j in 0..q.len() {
                let acc = (q[j] - 2.0 * b[j] + a[j]) / (dt * dt);
                let limit = self.config.joints[j].max_acceleration;
                assert!(
                    acc.abs() <= limit * (1.0 + 1e-9),
                    "tick {}: joint {j} at {acc} rad/s² (limit {limit})",
                    self.ticks
                );
            }
        }
        if let Err(entry) = self.body.check(&q) {
            panic!(
                "tick {}: {} entered (gap {} m) at {q:?}",
                self.ticks, entry.hit, entry.gap
            );
        }
        self.last.push(q);
        if self.last.len() > 2 {
            self.last.remove(0);
        }
        let p = ctrl.chain().forward(&q).unwrap().translation.vector;
        let now = self.boxes_holding(&p);
        for (k, (was, is)) in self.inside.iter().zip(&now).enumerate() {
            assert!(
                !is || *was,
                "tick {}: the tool entered box {k} at {p:?}",
                self.ticks
            );
        }
        self.inside = now;
    }
}

/// Runs `requests` random requests; returns how many following-error stops began, and the
/// least clearance of the arm's body seen (m).
fn run(config: ValidRobot, start: &[f64], seed: u64, requests: usize) -> (usize, f64) {
    let mut ctrl = Controller::new(&config);
    let mut arm = IdealArm::new(Joints::from_slice(start).unwrap());
    let mut rng = SplitMix64::new(seed);
    let chain = ctrl.chain().clone();
    let p0 = chain.forward(&arm.measured()).unwrap().translation.vector;
    let mut oracle = Oracle {
        inside: Vec::new(),
        last: Vec::new(),
        setpoints: Vec::new(),
        ticks: 0,
        config: config.clone(),
        body: BodyOracle::new(&config, start),
    };
    oracle.inside = oracle.boxes_holding(&p0);
    let dt = config.control_period;
    let mut now = 0.0;
    // Ticks the arm is still held where it is, and the following-error stops seen.
    let (held, lagged) = (std::cell::Cell::new(0_u64), std::cell::Cell::new(0_usize));
    let mut step = |ctrl: &mut Controller, arm: &mut IdealArm, oracle: &mut Oracle| {
        now += dt;
        let stopping = ctrl.motion() == Motion::Stopping;
        let out = ctrl.step(now, &arm.measured()).unwrap();
        oracle.check(ctrl, out.command);
        oracle.check_setpoint(stopping, out.setpoint);
        lagged.set(lagged.get() + usize::from(out.events.following_error.is_some()));
        match held.get() {
            0 => arm.step(out.command.as_ref()),
            ticks => held.set(ticks - 1),
        }
    };
    step(&mut ctrl, &mut arm, &mut oracle);
    let c = &config.cartesian;
    // An ST or OF since the last move or zero stream that was accepted: no stream may start.
    let mut latched = false;
    // A stream request: refused while latched (unless zero, which re-arms), checked.
    let stream = |latched: &mut bool, zero: bool, result: Result<(), Refusal>| {
        if *latched && !zero {
            assert!(
                !matches!(result, Ok(())),
                "a stream started after a stop without re-arming"
            );
        }
        if zero && result.is_ok() {
            *latched = false;
        }
    };
    let mut lags_seen = 0;
    for _ in 0..requests {
        // A following-error stop latches as any stop.
        if lagged.get() > lags_seen {
            lags_seen = lagged.get();
            latched = true;
        }
        // So does a stream's timeout (its client went quiet while it moved the arm): its
        // cause stays in force until the re-arming that clears the latch too.
        latched |= ctrl.stop_cause().0 == Some(StopCause::StreamTimeout);
        match rng.next_u64() % 10 {
            0 => {
                let mode = [Mode::Off, Mode::Joint, Mode::Cartesian][(rng.next_u64() % 3) as usize];
                let _ = ctrl.set_mode(mode);
            }
            1 | 2 => {
                let q = arm.measured();
                let mut goal = q;
                for (j, g) in goal.iter_mut().enumerate() {
                    let (lo, hi) = (chain.min()[j], chain.max()[j]);
                    *g = (*g + rng.uniform(-0.5, 0.5)).clamp(lo, hi);
                }
                if ctrl.move_joints(&goal, 0.0).is_ok() {
                    latched = false;
                }
            }
            3 | 4 => {
                let pose = chain.forward(&arm.measured()).unwrap();
                let offset = Vector3::new(
                    rng.uniform(-0.15, 0.15),
                    rng.uniform(-0.15, 0.15),
                    rng.uniform(-0.15, 0.15),
                );
                let goal =
                    Frame::from_parts((pose.translation.vector + offset).into(), pose.rotation);
                if ctrl.move_cartesian(goal, 0.0).is_ok() {
                    latched = false;
                }
            }
            5 => {
                let mut v = |k: usize| rng.uniform(-1.0, 1.0) * c.max_velocity[k];
                let twist = Twist::new(v(0), v(1), v(2), 0.0, 0.0, 0.0);
                // Half the streams start on purpose: a zero twist first.
                if rng.next_u64().is_multiple_of(2) {
                    let zero = ctrl.stream_twist(Twist::zeros(), TwistFrame::Base);
                    stream(&mut latched, true, zero);
                }
                for _ in 0..(rng.next_u64() % 60) {
                    let result = ctrl.stream_twist(twist, TwistFrame::Base);
                    stream(&mut latched, false, result);
                    step(&mut ctrl, &mut arm, &mut oracle);
                }
            }
            6 => {
                let rates: Vec<f64> = config
                    .joints
                    .iter()
                    .map(|j| rng.uniform(-1.0, 1.0) * j.max_velocity.min(j.max_rate))
                    .collect();
                if rng.next_u64().is_multiple_of(2) {
                    let zero = ctrl.stream_joint_rates(&vec![0.0; rates.len()]);
                    stream(&mut latched, true, zero);
                }
                for _ in 0..(rng.next_u64() % 60) {
                    let result = ctrl.stream_joint_rates(&rates);
                    stream(&mut latched, false, result);
                    step(&mut ctrl, &mut arm, &mut oracle);
                }
            }
            7 => {
                ctrl.stop(StopCause::Stop);
                latched = true;
            }
            8 => {
                ctrl.stop(StopCause::PowerOff);
                latched = true;
            }
            _ => held.set(10 + rng.next_u64() % 60),
        }
        for _ in 0..(rng.next_u64() % 120) {
            step(&mut ctrl, &mut arm, &mut oracle);
        }
    }
    let clearance = oracle.body.nearest().map_or(f64::INFINITY, |(gap, _)| gap);
    (lagged.get(), clearance)
}

#[test]
fn random_requests_never_exceed_the_acceleration_or_bring_a_link_into_contact() {
    // ranger-mk1 with a box in front of the ready pose's tool, besides its column.
    const READY: [f64; 6] = [1.5708, 0.6, -0.4, 0.2, 1.8, 0.1];
    let ranger = common::robot("ranger-mk1")
        .edit(|c| {
            c.cartesian.max_velocity = [0.1, 0.1, 0.1, 0.3, 0.3, 0.3];
            c.cartesian.max_acceleration = [0.2, 0.2, 0.2, 0.5, 0.5, 0.5];
            c.workspace
                .boxes
                .push([-0.15, 0.05, 0.85, 0.95, 1.1, 1.4])
                .unwrap();
        })
        .unwrap();
    let (mut lagged, mut least) = (0, f64::INFINITY);
    let mut tally = |(lags, clearance): (usize, f64)| {
        lagged += lags;
        least = least.min(clearance);
    };
    for seed in 0..6 {
        tally(run(ranger.clone(), &READY, seed, 60));
    }
    let ur5 = common::robot("ur5");
    let mid = Controller::new(&ur5).chain().mid_range();
    for seed in 0..3 {
        tally(run(ur5.clone(), &mid, 100 + seed, 60));
    }
    eprintln!("least clearance of the arm's body: {:.2} mm", least * 1e3);
    assert!(lagged > 0, "no following-error stop was tried");
}
