//! Talking to simulated Whistles frame by frame on a virtual bus, without a drive manager.

use armgate_core::drives::CanBus;
use armgate_core::sim::{SimWhistle, VirtualBus, WhistleConfig};
use armgate_protocol::can::interpreter::{Index, Mnemonic, Request, Value};
use armgate_protocol::can::{CanFrame, NodeId, NodeMessage};

use super::robot;

/// The simulated drive of ranger-mk1's joint `joint` (0-based; node 101 + joint).
pub fn whistle(joint: usize) -> SimWhistle {
    let config = robot("ranger-mk1");
    SimWhistle::new(WhistleConfig::for_joint(&config.joints[joint]).unwrap())
}

/// The interpreter command `command[index] = value` to `node`.
pub fn set(node: u8, command: Mnemonic, index: u8, value: i32) -> CanFrame {
    Request::Set {
        command,
        index: Index::from(index),
        value: Value::Int(value),
    }
    .to_frame(NodeId::new(node).unwrap())
}

/// The interpreter query (or action) `command[index]` to `node`.
pub fn query(node: u8, command: Mnemonic, index: u8) -> CanFrame {
    Request::Query {
        command,
        index: Index::from(index),
    }
    .to_frame(NodeId::new(node).unwrap())
}

/// Sends `frames` and runs the bus for `seconds`, returning what the controller received.
pub fn exchange(bus: &mut VirtualBus, frames: &[CanFrame], seconds: f64) -> Vec<CanFrame> {
    for frame in frames {
        bus.try_transmit(frame).unwrap();
    }
    bus.advance(bus.now() + seconds).unwrap();
    std::iter::from_fn(|| bus.try_receive()).collect()
}

/// Motor on and a cyclic PT ring QP[1..=6] on `node`: `samples` per segment, the queue-low
/// threshold `MP[5]`, the write pointer `MP[6]` at 1. One command per millisecond.
pub fn pt_ring(bus: &mut VirtualBus, node: u8, samples: i32, queue_low: i32) {
    let setup = [
        set(node, Mnemonic::MO, 0, 1),
        set(node, Mnemonic::MP, 1, 1),
        set(node, Mnemonic::MP, 2, 6),
        set(node, Mnemonic::MP, 3, 1),
        set(node, Mnemonic::MP, 4, samples),
        set(node, Mnemonic::MP, 5, queue_low),
        set(node, Mnemonic::MP, 6, 1),
    ];
    for frame in setup {
        exchange(bus, &[frame], 0.001);
    }
}
