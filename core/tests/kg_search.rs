//! `KG` on a chain without a closed form (issue 33): its global search runs in slices of at
//! most `SEARCH_SLICE` Newton steps, one a tick (the per-slice bound is counted step by step in
//! `kinematics::global`'s tests), and the `KG` is answered when it ends, with the answer the
//! whole search gives. Other clients are served meanwhile, the searching client's next
//! requests wait behind it, and a stop cancels it.
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod common;

use std::net::SocketAddr;

use armgate_core::config::ValidRobot;
use armgate_core::cycle::{Cycle, Datagram, SEARCH_SLICE};
use armgate_core::kinematics::{Chain, Family, IkResult, Joints};
use armgate_core::math;
use armgate_core::sim::{ArmModel, IdealArm, SimulatedDrives};
use common::clients::{Clients, reply_text};
use common::{datagram, floats};

const JOINT: [f32; 7] = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
/// `KG` index: the solution nearest the present joints (the only one without a closed form).
const NEAREST: u8 = 8;

fn a() -> SocketAddr {
    SocketAddr::from(([192, 168, 1, 2], 5000))
}

fn b() -> SocketAddr {
    SocketAddr::from(([192, 168, 1, 3], 6000))
}

/// hybrid with its second slide moved to the third joint: no closed form.
fn numeric() -> ValidRobot {
    common::robot("hybrid")
        .edit(|c| c.joints.swap(1, 2))
        .unwrap()
}

struct Rig {
    cycle: Cycle<SimulatedDrives, SocketAddr>,
    clients: Clients,
    chain: Chain,
    config: ValidRobot,
}

impl Rig {
    fn new() -> Self {
        let config = numeric();
        let chain = Chain::new(&config);
        assert_eq!(chain.family().family, Family::Numeric);
        let arm = IdealArm::new(chain.mid_range());
        let mut rig = Self {
            cycle: Cycle::new(&config, SimulatedDrives::new(ArmModel::Ideal(arm))),
            clients: Clients::default(),
            chain,
            config,
        };
        rig.tick();
        let reply = rig.cycle.answer(&datagram("CM", JOINT, 0), a());
        assert_eq!(&reply[..2], b"MC");
        rig
    }

    fn tick(&mut self) {
        let due = self.cycle.next_due_us();
        self.cycle.tick(due, &mut self.clients).step.unwrap();
    }

    /// Queues a request from `client` for the next tick.
    fn queue(&mut self, client: SocketAddr, cmd: &str, values: [f32; 7], index: u8) {
        let request = datagram(cmd, values, index);
        self.clients
            .requests
            .push_back(Datagram::new(&request, client));
    }

    /// Ticks until `client` has a reply (at most `limit` ticks): the reply and the ticks.
    fn answer_to(&mut self, client: SocketAddr, limit: usize) -> (String, usize) {
        for ticks in 1..=limit {
            self.tick();
            if let Some(i) = self.clients.replies.iter().position(|(c, _)| *c == client) {
                return (self.clients.replies.remove(i).1, ticks);
            }
        }
        panic!("no reply to {client} within {limit} ticks");
    }

    fn joints(&mut self) -> Joints {
        let reply = self.cycle.answer(&datagram("jP", [0.0; 7], 0), b());
        let q: Vec<f64> = floats(&reply)[..6].iter().map(|v| f64::from(*v)).collect();
        Joints::from_slice(&q).unwrap()
    }
}

/// `KG`'s values for `pose` (T = 0).
fn kg_values(pose: &math::Frame) -> [f32; 7] {
    let [r, p, y] = math::rpy(&pose.rotation);
    let t = pose.translation.vector;
    [t.x, t.y, t.z, r, p, y, 0.0].map(|v| v as f32)
}

/// To a goal out of reach the search spends its whole budget, a slice a tick: the refusal
/// comes after at least budget / slice ticks, during which another client's reads are
/// answered every tick and the searching client's next request waits behind its `KG`.
#[test]
fn an_unreachable_kg_searches_a_slice_a_tick_and_is_refused_at_the_end() {
    let mut rig = Rig::new();
    let budget = usize::from(rig.config.ik.global_iterations);
    let far = math::Frame::from_parts(
        math::Vector3::new(10.0, 0.0, 0.3).into(),
        math::Rotation3::identity(),
    );
    rig.queue(a(), "KG", kg_values(&far), NEAREST);
    rig.queue(a(), "jP", [0.0; 7], 0);
    let mut ticks = 0;
    let refusal = loop {
        rig.queue(b(), "PS", [0.0; 7], 0);
        rig.tick();
        ticks += 1;
        assert!(ticks < 10 * budget, "no answer");
        let replies: Vec<_> = rig.clients.replies.drain(..).collect();
        assert!(replies.contains(&(b(), "SP".into())), "B's read waited");
        if let Some((_, text)) = replies.iter().find(|(c, _)| *c == a()) {
            break text.clone();
        }
    };
    assert_eq!(refusal, "ER25 Cmd KG unreachable");
    // A's jP waited behind its KG: answered only now.
    assert_eq!(rig.answer_to(a(), 2), ("Pj".to_string(), 1));
    let slices = budget.div_ceil(usize::from(SEARCH_SLICE));
    println!("unreachable KG: {budget} steps, answered after {ticks} ticks");
    assert!(ticks >= slices, "{ticks} ticks for {budget} steps");
}

/// A reachable goal gets the answer of the whole search (`solve_global` from the present
/// joints), and the arm moves there.
#[test]
fn a_reachable_kg_gives_the_whole_searchs_answer_and_arrives() {
    let mut rig = Rig::new();
    let present = rig.joints();
    let mut q = present;
    for (i, v) in q.iter_mut().enumerate() {
        *v += if i % 2 == 0 { 0.05 } else { -0.04 };
    }
    // The goal as the wire carries it (f32), so that both solve the same pose.
    let values = kg_values(&rig.chain.forward(&q).unwrap());
    let v = values.map(f64::from);
    let goal = math::Frame::from_parts(
        math::Vector3::new(v[0], v[1], v[2]).into(),
        math::Rotation3::from_euler_angles(v[3], v[4], v[5]),
    );
    let expected = match rig
        .chain
        .solve_global(&goal, &present, &rig.config.ik, 0)
        .unwrap()
    {
        IkResult::Converged(s) => s.q,
        other => panic!("not reachable: {other:?}"),
    };
    rig.queue(a(), "KG", values, NEAREST);
    let (reply, ticks) = rig.answer_to(a(), 1000);
    assert_eq!(reply, "GK");
    println!("reachable KG answered after {ticks} ticks");
    for _ in 0..600 {
        rig.tick();
    }
    let reached = rig.joints();
    for (r, e) in reached.iter().zip(expected.iter()) {
        assert!((r - e).abs() < 1e-5, "{reached:?} vs {expected:?}");
    }
}

/// A stop cancels a `KG` still searching: answered `ER42`, and the arm does not move.
#[test]
fn a_stop_cancels_a_kg_still_searching() {
    let mut rig = Rig::new();
    let before = rig.joints();
    let far = math::Frame::from_parts(
        math::Vector3::new(10.0, 0.0, 0.3).into(),
        math::Rotation3::identity(),
    );
    rig.queue(a(), "KG", kg_values(&far), NEAREST);
    rig.tick();
    rig.tick();
    assert!(rig.clients.replies.is_empty(), "still searching");
    rig.queue(b(), "ST", [0.0; 7], 0);
    rig.tick();
    let replies: Vec<_> = rig.clients.replies.drain(..).collect();
    assert_eq!(
        replies,
        [
            (a(), "ER42 Cmd KG cancelled by ST".to_string()),
            (b(), "TS".to_string())
        ]
    );
    for _ in 0..100 {
        rig.tick();
    }
    assert!(rig.clients.replies.is_empty(), "nothing more");
    assert_eq!(rig.joints(), before);
    assert_eq!(
        reply_text(&rig.cycle.answer(&datagram("SQ", [0.0; 7], 0), b()))[..2],
        *"QS"
    );
}
