//! Stop latency on the bus: from an `ST` datagram's arrival to the first decelerating set-point
//! the drive manager puts on the CAN bus, in control ticks, on both streaming schedules
//! (interpreter: `QP` writes; PDO: RPDO3 points), simulated Whistles on the virtual bus.
//!
//! ```sh
//! cargo run --release -p armgate-core --example stop_latency
//! ```
//!
//! ranger-mk1 runs a joint move of joint 1 at cruise (0.07 rad/s); the `ST` datagram is queued
//! for the next tick, as a datagram that arrived during the period before it. A tick handles
//! its requests after the control step and the drives' transmit (docs/architecture.md), so
//! the stop's first decelerating command is computed, and sent, by the tick after the one that
//! handled `ST`. The figure counts ticks from the tick that handled the datagram to the tick
//! whose frames carry the first point of joint 1's drive with a smaller step than at cruise;
//! the datagram itself arrived up to one period before the handling tick.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::approx_constant // the seed's home angles, as it wrote them
)]

use std::path::PathBuf;

#[path = "../tests/drives_rig/mod.rs"]
mod drives_rig;
use drives_rig::{MK1_READY, Rig, request};

use armgate_core::config::{Streaming, ValidRobot, load_file};
use armgate_core::motion::Mode;
use armgate_protocol::can::CanFrame;
use armgate_protocol::can::interpreter::{Mnemonic, Request, Value};
use armgate_protocol::can::pdo::PtPoint;
use armgate_protocol::can::{NodeId, NodeMessage};
use armgate_protocol::client::Command;

/// Ticks of cruise before each stop, one stop per offset (the stop lands on different points
/// of the drives' cycle).
const CRUISE_TICKS: [usize; 4] = [20, 21, 22, 23];

fn robot(streaming: Streaming) -> ValidRobot {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../robots/ranger-mk1.toml");
    load_file(&path)
        .expect("robot file")
        .edit(|config| config.drives.streaming = streaming)
        .expect("the robot file's period carries both schedules")
}

/// The set-point (counts) for `node` in `frame`, if the frame carries one.
fn point(frame: &CanFrame, node: NodeId) -> Option<i32> {
    if let Ok((n, PtPoint { position })) = PtPoint::parse(frame) {
        return (n == node).then_some(position);
    }
    match Request::parse(frame) {
        Ok((
            n,
            Request::Set {
                command,
                value: Value::Int(counts),
                ..
            },
        )) if n == node && command == Mnemonic::QP => Some(counts),
        _ => None,
    }
}

/// Ticks from the tick that handled `ST` to the one that sent the first decelerating point,
/// after `cruise` ticks of a joint-1 move.
fn latency(config: &ValidRobot, cruise: usize) -> usize {
    let mut rig = Rig::running(config);
    rig.ctrl_mut().set_mode(Mode::Joint).unwrap();
    rig.tick();
    let mut goal = MK1_READY;
    goal[0] += 1.0;
    rig.ctrl_mut().move_joints(&goal, 0.0).unwrap();
    let node = NodeId::new(config.config().joints[0].drive.node_id).unwrap();
    // (tick, counts) of joint 1's points, in the order sent.
    let mut points: Vec<(usize, i32)> = Vec::new();
    let record = |rig: &Rig, tick: usize, points: &mut Vec<(usize, i32)>| {
        points.extend(
            rig.sent()
                .iter()
                .filter_map(|f| point(f, node))
                .map(|c| (tick, c)),
        );
    };
    // Up to speed (0.14 s), then cruise.
    for k in 0..cruise {
        rig.tick();
        record(&rig, k, &mut points);
    }
    let cruise_step = points.windows(2).last().map(|w| w[1].1 - w[0].1).unwrap();
    rig.client.requests.push_back(request(Command::Stop));
    let handled = cruise;
    for k in cruise..cruise + 20 {
        rig.tick();
        record(&rig, k, &mut points);
    }
    let first = points
        .windows(2)
        .find(|w| w[1].0 >= handled && (w[1].1 - w[0].1).abs() + 2 < cruise_step.abs())
        .expect("a decelerating point");
    first[1].0 - handled
}

fn main() {
    println!(
        "| schedule | period | ticks from the tick that handled ST to the first decelerating point on the bus (per stop) |"
    );
    println!("|---|---|---|");
    for streaming in [Streaming::Interpreter, Streaming::Pdo] {
        let config = robot(streaming);
        let ticks: Vec<String> = CRUISE_TICKS
            .iter()
            .map(|&c| latency(&config, c).to_string())
            .collect();
        println!(
            "| {streaming:?} | {:.2} ms | {} |",
            config.control_period * 1e3,
            ticks.join(", ")
        );
    }
    println!(
        "\n(simulated: ST arrives up to one period before the tick that handles it, so from the \
         datagram's arrival that many ticks plus up to one period; the drives then reach a point \
         within about two set-points, docs/drives.md 'latency write -> reached')"
    );
}
