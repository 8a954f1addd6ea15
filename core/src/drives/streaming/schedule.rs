//! Which query each drive sends in each cycle, besides its PT point.
//!
//! Every streaming cycle a drive gets at most two interpreter frames: its PT point (`QP`) and
//! one query. The seed's rule (spec §6.5) is kept: the thesis saw a Whistle lose a third frame
//! that arrived while one command ran and one waited. The query is usually the position (`PX`),
//! so the measurement is at most one cycle old; every `read_index_every` cycles it is the PT
//! read index, and every `temperature_every` cycles the temperature. The reads are staggered
//! over the drives, so every cycle carries the same number of frames.

use armgate_protocol::can::interpreter::{Index, Mnemonic, Request};

use crate::config::bus_load::TEMPERATURE_EVERY;

/// What a drive is asked for in one cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Query {
    /// Main position `PX` (counts).
    Position,
    /// The PT read index (`PT`), for flow control.
    ReadIndex,
    /// Drive temperature `TI[1]` (°C).
    Temperature,
}

impl Query {
    /// The interpreter request.
    pub fn request(self) -> Request {
        let (command, index) = match self {
            Self::Position => (Mnemonic::PX, 0),
            Self::ReadIndex => (Mnemonic::PT, 0),
            Self::Temperature => (Mnemonic::TI, 1),
        };
        Request::Query {
            command,
            index: Index::from(index),
        }
    }
}

/// How often the drives are asked for their read index and temperature.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Schedule {
    /// A drive reads its PT read index every this many cycles (at least 1).
    pub read_index_every: u16,
    /// A drive reads its temperature every this many cycles (at least 1); it takes precedence
    /// over the read index when both fall due.
    pub temperature_every: u16,
    /// For this many cycles after the motion starts, every drive reads its read index every
    /// other cycle (its position in between), so the flow control settles at once.
    pub settle_cycles: u16,
}

impl Default for Schedule {
    fn default() -> Self {
        Self {
            read_index_every: 6,
            temperature_every: TEMPERATURE_EVERY,
            settle_cycles: 8,
        }
    }
}

impl Schedule {
    /// True if cycle `cycle` (`k` staggered for the drive) reads the read index.
    fn reads_index(&self, cycle: u32, k: u32) -> bool {
        if cycle < u32::from(self.settle_cycles) {
            cycle.is_multiple_of(2)
        } else {
            k.is_multiple_of(u32::from(self.read_index_every.max(1)))
        }
    }

    /// The query of drive `drive` (0-based among the drives) in streaming cycle `cycle`
    /// (counted from the start of the motion). With `pacing` false (no PT motion to pace), the
    /// read index is never asked for.
    pub fn query(&self, cycle: u32, drive: usize, pacing: bool) -> Query {
        let k = cycle.wrapping_add(drive as u32);
        let every = |n: u16| u32::from(n.max(1));
        if k % every(self.temperature_every) == every(self.temperature_every) / 2 {
            Query::Temperature
        } else if pacing && self.reads_index(cycle, k) {
            Query::ReadIndex
        } else {
            Query::Position
        }
    }
}
