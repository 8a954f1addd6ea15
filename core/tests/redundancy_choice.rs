//! `KR`: a client chooses the redundancy parameters (θ3, and θ5 on eight joints) of its next
//! `KG` and of its `KS` reads (docs/protocol.md, docs/kinematics.md "Redundant arms").
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]
// The seed deployed rounded angles such as 1.5708.
#![allow(clippy::approx_constant)]

mod common;

use common::{datagram, floats};

use std::net::SocketAddr;

use armgate_core::cycle::{Cycle, Datagram, Dropped, Link, Outgoing};
use armgate_core::kinematics::{Chain, Joints};
use armgate_core::math;
use armgate_core::sim::{ArmModel, IdealArm, SimulatedDrives};

/// KG and KS index bit: with this client's KR choice.
const CHOSEN: u8 = 0x40;
/// KG index: the solution nearest the present joints.
const NEAREST: u8 = 8;

/// A link that delivers nothing: the test answers requests between ticks.
struct Quiet;

impl Link<SocketAddr> for Quiet {
    fn receive(&mut self) -> Option<Datagram<SocketAddr>> {
        None
    }

    fn send(&mut self, _: &Datagram<SocketAddr>, _: Outgoing) -> Result<(), Dropped> {
        Ok(())
    }
}

struct Rig {
    cycle: Cycle<SimulatedDrives, SocketAddr>,
    chain: Chain,
    now: f64,
}

fn client(port: u16) -> SocketAddr {
    SocketAddr::from(([192, 168, 1, 2], port))
}

impl Rig {
    fn new(robot: &str, q0: &[f64]) -> Self {
        let config = common::robot(robot);
        let arm = IdealArm::new(Joints::from_slice(q0).unwrap());
        let mut rig = Self {
            cycle: Cycle::new(&config, SimulatedDrives::new(ArmModel::Ideal(arm))),
            chain: Chain::new(&config),
            now: 0.0,
        };
        rig.tick();
        rig
    }

    fn tick(&mut self) {
        let due = self.cycle.next_due_us();
        let outcome = self.cycle.tick(due, &mut Quiet);
        outcome.step.unwrap();
        self.now = outcome.time;
    }

    fn run_for(&mut self, seconds: f64) {
        let until = self.now + seconds;
        while self.now < until {
            self.tick();
        }
    }

    /// The reply to `cmd` from the client on `port`.
    fn from(&mut self, port: u16, cmd: &str, values: [f32; 7], index: u8) -> [u8; 31] {
        self.cycle
            .answer(&datagram(cmd, values, index), client(port))
    }

    /// The same, from client 1.
    fn request(&mut self, cmd: &str, values: [f32; 7], index: u8) -> [u8; 31] {
        self.from(1, cmd, values, index)
    }

    /// The reply's text (an ER/WN answer), or its two characters.
    fn text(&mut self, port: u16, cmd: &str, values: [f32; 7], index: u8) -> String {
        let reply = self.from(port, cmd, values, index);
        let end = reply.iter().position(|b| *b == 0).unwrap_or(2);
        String::from_utf8_lossy(&reply[..end]).into_owned()
    }

    /// The measured joints, all of them (jP banks 1 and 2).
    fn joints(&mut self) -> Vec<f64> {
        let n = self.chain.dof();
        let mut q: Vec<f64> = floats(&self.request("jP", [0.0; 7], 0))[..6.min(n)]
            .iter()
            .map(|v| f64::from(*v))
            .collect();
        if n > 6 {
            let upper = floats(&self.request("jP", [0.0; 7], 0x80));
            q.extend(upper[..n - 6].iter().map(|v| f64::from(*v)));
        }
        q
    }

    /// KG's values for the pose of `q` (T = 0).
    fn pose_of(&self, q: &[f64]) -> [f32; 7] {
        let pose = self.chain.forward(q).unwrap();
        let [r, p, y] = math::rpy(&pose.rotation);
        let t = pose.translation.vector;
        [t.x, t.y, t.z, r, p, y, 0.0].map(|v| v as f32)
    }
}

/// KR's values: θ3 in f0, θ5 in f1.
fn kr(theta3: f32, theta5: f32) -> [f32; 7] {
    [theta3, theta5, 0.0, 0.0, 0.0, 0.0, 0.0]
}

/// KR then KG reaches the pose with the chosen parameters; the arm ends there.
fn moves_with_chosen_parameters(robot: &str, present: &[f64], target: &[f64], index: u8) {
    let mut rig = Rig::new(robot, present);
    let goal = rig.pose_of(target);
    let parameters = rig.chain.redundancy_parameters().to_vec();
    let chosen: Vec<f32> = parameters.iter().map(|&p| target[p] as f32).collect();
    let values = kr(chosen[0], chosen.get(1).copied().unwrap_or(0.0));
    // Before a choice, KS and KG with CHOSEN are refused.
    assert!(rig.text(1, "KS", goal, CHOSEN).starts_with("ER24 Cmd KS"));
    let rk = rig.request("KR", values, index);
    assert_eq!((&rk[..2], rk[30]), (&b"RK"[..], index), "{robot}");
    assert_eq!(floats(&rk), values);
    // KS with the choice: every solution keeps the chosen values.
    let sk = rig.request("KS", goal, CHOSEN);
    assert_eq!(&sk[..2], b"SK");
    assert!(floats(&sk)[6] >= 1.0, "{robot}: {:?}", floats(&sk));
    for (&p, &v) in parameters.iter().zip(&chosen) {
        assert!(
            (floats(&sk)[p] - v).abs() < 1e-6,
            "{robot}: {:?}",
            floats(&sk)
        );
    }
    rig.request("CM", [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 0);
    rig.tick();
    let gk = rig.request("KG", goal, NEAREST | CHOSEN);
    assert_eq!(
        &gk[..2],
        b"GK",
        "{robot}: {:?}",
        String::from_utf8_lossy(&gk)
    );
    assert!(gk[30] < 8);
    for (&p, &v) in parameters.iter().zip(&chosen) {
        assert!(
            (floats(&gk)[p] - v).abs() < 1e-6,
            "{robot}: {:?}",
            floats(&gk)
        );
    }
    // The choice was the KG's: the next one asking for it is refused.
    assert!(
        rig.text(1, "KG", goal, NEAREST | CHOSEN)
            .starts_with("ER24 Cmd KG")
    );
    rig.run_for(12.0);
    let q = rig.joints();
    for (&p, &v) in parameters.iter().zip(&chosen) {
        assert!((q[p] - f64::from(v)).abs() < 1e-4, "{robot}: {q:?}");
    }
    let reached = rig.chain.forward(&q).unwrap();
    let wanted = rig.chain.forward(target).unwrap();
    let miss = (reached.translation.vector - wanted.translation.vector).norm();
    assert!(miss < 1e-4, "{robot}: {miss} m, {q:?}");
    let turn = (reached.rotation.inverse() * wanted.rotation).angle();
    assert!(turn < 1e-4, "{robot}: {turn} rad");
}

#[test]
fn iiwa14_moves_to_a_pose_with_the_chosen_theta3() {
    let present = [0.1, 0.5, 0.3, -1.0, 0.2, 0.8, 0.1];
    // Another θ3 than the present one, and than the one the present θ3 would give.
    let target = [0.3, 0.7, -0.6, -1.2, 0.4, 0.6, -0.2];
    moves_with_chosen_parameters("iiwa14", &present, &target, 1);
}

#[test]
fn ranger_mk2_moves_to_a_pose_with_the_chosen_theta3_and_theta5() {
    let present = [0.1, 0.5, 0.3, -1.0, 0.2, 0.8, 0.1, 0.2];
    let target = [0.3, 0.7, -0.5, -1.2, 0.6, 0.6, -0.2, 0.4];
    moves_with_chosen_parameters("ranger-mk2", &present, &target, 3);
}

#[test]
fn a_choice_is_refused_where_the_arm_has_no_such_parameter_or_limit() {
    let mut mk1 = Rig::new("ranger-mk1", &[1.5708, 0.6, -0.4, 0.2, 1.8, 0.1]);
    assert!(
        mk1.text(1, "KR", kr(0.1, 0.0), 1)
            .starts_with("ER24 Cmd KR")
    );
    assert!(
        mk1.text(1, "KR", kr(0.0, 0.0), 0)
            .starts_with("ER24 Cmd KR")
    );
    let mut iiwa = Rig::new("iiwa14", &[0.1, 0.5, 0.3, -1.0, 0.2, 0.8, 0.1]);
    // Seven joints: no θ5; an unknown index bit; a non-finite value; beyond j3's limits.
    assert!(
        iiwa.text(1, "KR", kr(0.1, 0.2), 3)
            .starts_with("ER24 Cmd KR")
    );
    assert!(
        iiwa.text(1, "KR", kr(0.1, 0.0), 5)
            .starts_with("ER24 Cmd KR")
    );
    assert!(
        iiwa.text(1, "KR", kr(f32::NAN, 0.0), 1)
            .starts_with("ER23 Cmd KR")
    );
    assert_eq!(
        iiwa.text(1, "KR", kr(3.0, 0.0), 1),
        "ER26 Cmd KR j3 > 2.967"
    );
    assert_eq!(
        iiwa.text(1, "KR", kr(-3.0, 0.0), 1),
        "ER26 Cmd KR j3 < -2.967"
    );
    // Index 0 chooses nothing: KG with CHOSEN then keeps the present values.
    let rk = iiwa.request("KR", kr(0.7, 0.9), 0);
    assert_eq!((&rk[..2], floats(&rk), rk[30]), (&b"RK"[..], [0.0; 7], 0));
    let mut mk2 = Rig::new("ranger-mk2", &[0.1, 0.5, 0.3, -1.0, 0.2, 0.8, 0.1, 0.2]);
    assert_eq!(mk2.text(1, "KR", kr(0.0, 3.5), 2), "ER26 Cmd KR j5 > 3.142");
    assert_eq!(&mk2.request("KR", kr(0.0, 3.0), 2)[..2], b"RK");
}

#[test]
fn a_stop_clears_the_choice() {
    let present = [0.1, 0.5, 0.3, -1.0, 0.2, 0.8, 0.1];
    let mut rig = Rig::new("iiwa14", &present);
    let goal = rig.pose_of(&present);
    rig.request("CM", [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 0);
    rig.tick();
    rig.request("KR", kr(0.4, 0.0), 1);
    // A stop from another client clears it too (anyone may stop the arm).
    assert_eq!(&rig.from(2, "ST", [0.0; 7], 0)[..2], b"TS");
    assert!(rig.text(1, "KS", goal, CHOSEN).starts_with("ER24 Cmd KS"));
    assert!(
        rig.text(1, "KG", goal, NEAREST | CHOSEN)
            .starts_with("ER24 Cmd KG")
    );
    // Without CHOSEN, KG keeps the present θ3.
    let gk = rig.request("KG", goal, NEAREST);
    assert!((f64::from(floats(&gk)[2]) - present[2]).abs() < 1e-6);
}

#[test]
fn only_the_holder_chooses_and_a_new_holder_clears_the_choice() {
    let present = [0.1, 0.5, 0.3, -1.0, 0.2, 0.8, 0.1];
    let target = [0.3, 0.7, -0.6, -1.2, 0.4, 0.6, -0.2];
    let mut rig = Rig::new("iiwa14", &present);
    let goal = rig.pose_of(&target);
    rig.request("CM", [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 0);
    rig.tick();
    rig.request("KR", kr(-0.6, 0.0), 1);
    // Client 2 reads with its own (absent) choice, not client 1's.
    assert!(rig.text(2, "KS", goal, CHOSEN).starts_with("ER24 Cmd KS"));
    assert_eq!(&rig.request("KG", goal, NEAREST | CHOSEN)[..2], b"GK");
    rig.tick();
    // While client 1's move runs, client 2 can neither choose nor move.
    assert!(
        rig.text(2, "KR", kr(0.1, 0.0), 1)
            .starts_with("ER40 Cmd KR by 192.168.1.2")
    );
    assert!(
        rig.text(2, "KG", goal, NEAREST)
            .starts_with("ER40 Cmd KG by 192.168.1.2")
    );
    rig.run_for(12.0);
    // At rest: client 1 chooses, client 2 takes control (a new holder), client 1's choice is
    // gone.
    assert_eq!(&rig.request("KR", kr(0.2, 0.0), 1)[..2], b"RK");
    assert_eq!(&rig.from(2, "jC", [0.0; 7], 0)[..2], b"Cj");
    assert!(
        rig.text(1, "KG", goal, NEAREST | CHOSEN)
            .starts_with("ER24 Cmd KG")
    );
}
