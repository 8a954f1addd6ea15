//! One drive's start sequence (spec §6.4 "Start" and §6.6 "Initialisation").
//!
//! Each step sends at most two frames and completes when the drive has answered all of them,
//! so no drive ever gets more than two frames per cycle. (The seed sent twelve in one cycle
//! and waited with sleeps, §9 item 31; it also wrote the unused QT table and the write pointer
//! `MP[6]`, which interpreter writes by index do not use — both dropped here.)
//!
//! | Step | Frames | Meaning |
//! |---|---|---|
//! | `ConsumerHeartbeat` | SDO 0x1016:1 | stop by yourself if the controller's heartbeat stops |
//! | `ReadUnitMode` | `UM` | |
//! | `MotorOff`, `SetUnitMode` | `MO=0`, `UM=5` | only if the unit mode differs |
//! | `SettleUnitMode` | — | counted wait |
//! | `CheckUnitMode` | `UM` | must now be 5 |
//! | `MotorOn` | `MO=1` | |
//! | `ReadPosition` | `PX` | the start position and the first hold point |
//! | `Configure(0)` | `MP[1]=1`, `MP[2]=ring` | ring `QP[1..=ring]` |
//! | `Configure(1)` | `MP[3]=1`, `MP[4]=samples` | cyclic; segment = one control period |
//! | `Configure(2)` | `MP[5]=0`, `QP[1]=PX` | no queue-low warning: the read index paces the writer |
//! | `Configure(3)` | `QP[2]=PX`, `QP[3]=PX` | |
//! | `Configure(4)` | `PT=1` | the next `BG` starts PT motion at `QP[1]` |
//! | `Ready` | — | waits for every drive |
//! | `Begin` | `BG` | all drives in one cycle |
//!
//! The ring is filled with one point more than the lead the stream keeps: `QP[1..=3]` on the
//! interpreter schedule ([`FILLED_POINTS`](super::streaming::FILLED_POINTS)), `QP[1..=lead + 1]`
//! on the PDO schedule (at least `QP[1..=3]`: the first point streamed after `BG` is then due
//! at the second segment start), the fill going on two points per step before `PT=1`; the
//! stream then starts at its lead.
//!
//! The PDO schedule first gives every drive the group id (`GroupId`, SDO 0x2040), which takes
//! effect at a reset communication: when every drive has it (`Regroup`), the manager resets
//! the communication of all nodes, waits (`Rejoin`) and starts them again; one `BG` to the group
//! id then begins every drive at once. It adds the mapping after `ConsumerHeartbeat` — `Map(0..28)`, one SDO
//! transfer per step: each of protocol's [`streaming_mapping`] writes, then its read-back —
//! and sets the write pointer the receive PDO writes at (`WritePointer`, `MP[6]`) after
//! `Configure(1)`.

use armgate_protocol::can::interpreter::{Index, Mnemonic, Request, Value};
use armgate_protocol::can::{
    MAPPING_STEPS, MappingStep, NodeId, Object, SdoRequest, group_id_step, streaming_mapping,
};
use heapless::Vec;

use super::settings::POSITION_MODE;
use crate::config::Streaming;

/// Where one drive is in its start sequence.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StartStep {
    /// PDO schedule: write the group id (object 0x2040).
    GroupId,
    /// PDO schedule: read the group id back.
    CheckGroupId,
    /// PDO schedule: waiting for every drive to have its group id; then the reset
    /// communication goes out.
    Regroup,
    /// PDO schedule: after the reset communication, this many more cycles to wait; at 0 the
    /// NMT start goes out when every drive is there.
    Rejoin(u32),
    /// Configure the consumer heartbeat (object 0x1016).
    ConsumerHeartbeat,
    /// PDO schedule: the PDO mapping, transfer `n`: the write of mapping step `n / 2` (even
    /// `n`), or its read-back (odd `n`).
    Map(u8),
    /// Read the unit mode.
    ReadUnitMode,
    /// Switch the motor off before changing the unit mode.
    MotorOff,
    /// Set position mode.
    SetUnitMode,
    /// Wait this many more cycles after the change.
    SettleUnitMode(u32),
    /// Read the unit mode again.
    CheckUnitMode,
    /// Switch the motor on.
    MotorOn,
    /// Read the start position.
    ReadPosition,
    /// Configure the PT ring and fill it (two parts, then `MP[5]`, the fill and `PT=1` two
    /// frames a part).
    Configure(u8),
    /// PDO schedule: the write pointer (`MP[6]`) at the first free entry after the fill.
    WritePointer,
    /// Waiting for every other drive.
    Ready,
    /// `BG` sent: PT motion runs.
    Begin,
}

/// A frame a step sends, and the answer it waits for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Outgoing {
    /// An interpreter command; the answer echoes its command and index.
    Interpreter(Request),
    /// An SDO request; the answer names its object.
    Sdo(SdoRequest),
}

/// What a step needs to build its frames.
#[derive(Clone, Copy, Debug)]
pub struct StepContext {
    /// The controller, producer of the heartbeat the drives watch.
    pub controller: NodeId,
    /// The drives' consumer heartbeat time (ms).
    pub heartbeat_timeout_ms: u16,
    /// Entries of the PT ring.
    pub ring_len: u16,
    /// Samples per PT segment (`MP[4]`).
    pub samples_per_point: u16,
    /// The start position (counts), once read; the ring is filled with it.
    pub position: Option<i32>,
    /// Points filled with the start position before `BG`: `QP[1..=filled]`.
    pub filled: u16,
    /// The drive.
    pub node: NodeId,
    /// The group id the drives answer to besides their own (PDO schedule).
    pub group: NodeId,
}

impl StartStep {
    /// The first step of a start on `streaming`: the PDO schedule first gives every drive the
    /// group id.
    pub fn first(streaming: Streaming) -> Self {
        match streaming {
            Streaming::Interpreter => Self::ConsumerHeartbeat,
            Streaming::Pdo => Self::GroupId,
        }
    }

    /// The frames this step sends (at most two).
    pub fn frames(&self, ctx: &StepContext) -> Vec<Outgoing, 2> {
        let set = |command, index: u8, value: i32| {
            Outgoing::Interpreter(Request::Set {
                command,
                index: Index::from(index),
                value: Value::Int(value),
            })
        };
        let query = |command| {
            Outgoing::Interpreter(Request::Query {
                command,
                index: Index::ZERO,
            })
        };
        // No position, no fill: a point is never invented (and `BG` is then refused).
        let fill = |slot: u16| ctx.position.map(|p| set(Mnemonic::QP, slot as u8, p));
        // `Configure(2..)`: frame `i` of `MP[5]`, the fill, `PT=1`.
        let filling = |i: u16| match i {
            0 => Some(set(Mnemonic::MP, 5, 0)),
            i if i <= ctx.filled => fill(i),
            i if i == ctx.filled + 1 => Some(set(Mnemonic::PT, 0, 1)),
            _ => None,
        };
        let map = |n: u8| {
            mapping_step(ctx.node, n).map(|(step, read_back)| {
                Outgoing::Sdo(if read_back {
                    step.read_back()
                } else {
                    step.write()
                })
            })
        };
        let frames: &[Option<Outgoing>] = match *self {
            Self::ConsumerHeartbeat => &[Some(Outgoing::Sdo(SdoRequest::consumer_heartbeat(
                ctx.controller,
                ctx.heartbeat_timeout_ms,
            )))],
            Self::GroupId => &[Some(Outgoing::Sdo(group_id_step(ctx.group).write()))],
            Self::CheckGroupId => &[Some(Outgoing::Sdo(group_id_step(ctx.group).read_back()))],
            Self::Map(n) => &[map(n)],
            Self::WritePointer => &[Some(set(Mnemonic::MP, 6, i32::from(ctx.filled) + 1))],
            Self::ReadUnitMode | Self::CheckUnitMode => &[Some(query(Mnemonic::UM))],
            Self::MotorOff => &[Some(set(Mnemonic::MO, 0, 0))],
            Self::SetUnitMode => &[Some(set(Mnemonic::UM, 0, POSITION_MODE))],
            Self::MotorOn => &[Some(set(Mnemonic::MO, 0, 1))],
            Self::ReadPosition => &[Some(query(Mnemonic::PX))],
            Self::Configure(0) => &[
                Some(set(Mnemonic::MP, 1, 1)),
                Some(set(Mnemonic::MP, 2, i32::from(ctx.ring_len))),
            ],
            Self::Configure(1) => &[
                Some(set(Mnemonic::MP, 3, 1)),
                Some(set(Mnemonic::MP, 4, i32::from(ctx.samples_per_point))),
            ],
            Self::Configure(n) => {
                let first = 2 * u16::from(n.saturating_sub(2));
                &[filling(first), filling(first + 1)]
            }
            Self::Begin => &[Some(query(Mnemonic::BG))],
            Self::SettleUnitMode(_) | Self::Ready | Self::Regroup | Self::Rejoin(_) => &[],
        };
        // Pushed one by one: heapless's `collect` would panic on overflow (none here: at most
        // two per step).
        let mut out = Vec::new();
        for frame in frames.iter().flatten() {
            let _ = out.push(*frame);
        }
        out
    }

    /// The step after this one, given the unit mode the drive reported; `Err(found)` if the
    /// drive is still not in position mode after the change. `streaming`: the PDO schedule
    /// has steps of its own; `filled`: the points the ring is filled with.
    pub fn next(
        &self,
        unit_mode: Option<i32>,
        settle: u32,
        streaming: Streaming,
        filled: u16,
    ) -> Result<Self, i32> {
        let in_position_mode = unit_mode == Some(POSITION_MODE);
        let pdo = streaming == Streaming::Pdo;
        Ok(match *self {
            Self::GroupId => Self::CheckGroupId,
            Self::CheckGroupId | Self::Regroup => Self::Regroup,
            Self::Rejoin(n) => Self::Rejoin(n.saturating_sub(1)),
            Self::ConsumerHeartbeat if pdo => Self::Map(0),
            Self::ConsumerHeartbeat => Self::ReadUnitMode,
            Self::Map(n) if usize::from(n) + 1 < 2 * MAPPING_STEPS && pdo => Self::Map(n + 1),
            Self::Map(_) => Self::ReadUnitMode,
            Self::ReadUnitMode if in_position_mode => Self::MotorOn,
            Self::ReadUnitMode => Self::MotorOff,
            Self::MotorOff => Self::SetUnitMode,
            Self::SetUnitMode => Self::SettleUnitMode(settle),
            Self::SettleUnitMode(0) => Self::CheckUnitMode,
            Self::SettleUnitMode(n) => Self::SettleUnitMode(n - 1),
            Self::CheckUnitMode if in_position_mode => Self::MotorOn,
            Self::CheckUnitMode => return Err(unit_mode.unwrap_or(0)),
            Self::MotorOn => Self::ReadPosition,
            Self::ReadPosition => Self::Configure(0),
            Self::Configure(1) if pdo => Self::WritePointer,
            Self::WritePointer => Self::Configure(2),
            // The next part's first frame is 2 (n − 1) of `MP[5]`, the fill and `PT=1`.
            Self::Configure(n) if 2 * u16::from(n).saturating_sub(1) <= filled + 1 => {
                Self::Configure(n + 1)
            }
            Self::Configure(_) | Self::Ready => Self::Ready,
            Self::Begin => Self::Begin,
        })
    }
}

/// Transfer `n` of `node`'s PDO mapping: the step, and whether this transfer reads it back.
pub fn mapping_step(node: NodeId, n: u8) -> Option<(MappingStep, bool)> {
    let step = streaming_mapping(node).get(usize::from(n / 2)).copied()?;
    Some((step, n % 2 == 1))
}

impl StartStep {
    /// The PDO configuration transfer this step makes, if any: the step (group id or mapping)
    /// and whether it reads the value back.
    pub fn configuration(&self, node: NodeId, group: NodeId) -> Option<(MappingStep, bool)> {
        match *self {
            Self::GroupId => Some((group_id_step(group), false)),
            Self::CheckGroupId => Some((group_id_step(group), true)),
            Self::Map(n) => mapping_step(node, n),
            _ => None,
        }
    }
}

impl Outgoing {
    /// True if `reply` (command and index of an interpreter answer) answers this frame.
    pub fn answered_by(&self, command: Mnemonic, index: Index) -> bool {
        matches!(*self, Self::Interpreter(Request::Query { command: c, index: i }
            | Request::Set { command: c, index: i, .. }) if c == command && i == index)
    }

    /// True if an SDO answer about `object` answers this frame.
    pub fn answered_by_sdo(&self, object: Object) -> bool {
        matches!(*self, Self::Sdo(SdoRequest::Download { object: o, .. }
            | SdoRequest::Upload { object: o }) if o == object)
    }
}
