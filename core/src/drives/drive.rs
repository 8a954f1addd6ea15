//! What the manager knows about one joint and its drive.

use armgate_protocol::can::NodeId;
use heapless::Vec;

use super::link::Link;
use super::retry::Retry;
use super::startup::{Outgoing, StartStep};
use super::streaming::Stream;
use crate::config::JointUnits;

/// One joint: a real drive on the bus, or none (node id 0, the seed's "pretend" joint).
#[derive(Clone, Debug, PartialEq)]
pub enum Joint {
    /// No drive: the measurement mirrors the command (spec §6.1).
    Pretend {
        /// The last accepted command (rad or m), the home position at first.
        position: f64,
    },
    /// A drive on the bus.
    Real(Drive),
}

/// A drive on the bus.
#[derive(Clone, Debug, PartialEq)]
pub struct Drive {
    /// Its node id.
    pub node: NodeId,
    /// Counts ↔ position.
    pub units: JointUnits,
    /// The last position read (`PX`, counts).
    pub position: Option<i32>,
    /// The last temperature read (°C).
    pub temperature: Option<i32>,
    /// The last unit mode read.
    pub unit_mode: Option<i32>,
    /// The point streamed and held (counts): the start position, then the last accepted
    /// command.
    pub target: Option<i32>,
    /// Requests not yet answered.
    pub link: Link,
    /// Where the drive is in its start sequence.
    pub step: StartStep,
    /// The frames of the current start step not yet answered.
    pub awaiting: Vec<Outgoing, 2>,
    /// Whether the current step's frames went out.
    pub step_sent: bool,
    /// When they went out, and how often they were repeated.
    pub retry: Retry,
    /// The PT writer of the start's schedule, from `BG` until the motion stops.
    pub stream: Option<Stream>,
}

impl Drive {
    /// A drive not yet heard from.
    pub fn new(node: NodeId, units: JointUnits) -> Self {
        Self {
            node,
            units,
            position: None,
            temperature: None,
            unit_mode: None,
            target: None,
            link: Link::default(),
            step: StartStep::ConsumerHeartbeat,
            awaiting: Vec::new(),
            step_sent: false,
            retry: Retry::default(),
            stream: None,
        }
    }

    /// Back to the first start step, the motion over: after a stop, and before a start.
    pub fn reset_steps(&mut self) {
        self.step = StartStep::ConsumerHeartbeat;
        self.awaiting.clear();
        self.step_sent = false;
        self.stream = None;
    }
}
