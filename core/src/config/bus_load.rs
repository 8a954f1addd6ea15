//! Bus load of set-point streaming, and the fastest control period a bus carries.
//!
//! Every frame is counted at its worst-case length (stuff bits included, protocol's
//! [`bits_on_wire`]): a schedule that fits with the worst case fits whatever the data.
//!
//! * Interpreter schedule: per drive and cycle the manager sends its PT point (`QP`, 8 bytes)
//!   and one query (4 bytes), and the drive answers both (8 bytes each) — 500 bits whichever
//!   the query is.
//! * PDO schedule: one SYNC (0 bytes) per cycle; per drive one receive PDO with the PT point
//!   (4 bytes) and one transmit PDO with the position and the PT pointers (8 bytes) — 230
//!   bits; plus the temperature query and its answer once per `temperature_every` cycles per
//!   drive, counted as their average per cycle (the busiest cycle carries one more query and
//!   answer), and a Time Stamp (4 bytes) after every `time_stamp_every`-th SYNC, averaged the
//!   same way.
//!
//! The controller's heartbeat adds one 1-byte frame per heartbeat period to both.

use armgate_protocol::can::interpreter::{Index, Mnemonic, Reply, Request, Value};
use armgate_protocol::can::{
    Heartbeat, NmtState, NodeId, NodeMessage, PtFeedback, PtPoint, SyncObject, TimeStamp,
    bits_on_wire,
};

use super::drives::{Streaming, TIME_STAMP_EVERY};
use super::error::{ConfigError, ConfigReason};
use super::robot::RobotConfig;

/// The Whistle's position-loop sample time (SimplIQ default): PT points are spaced by a whole
/// number of these (`MP[4]`), so the control period is one too.
pub const SAMPLE_TIME: f64 = 360e-6;

/// The number of 360 µs drive samples in `period` seconds, if it is a whole number that fits a
/// `u16` (to 1e-3 of a sample: periods are written in decimal).
pub(crate) fn whole_samples(period: f64) -> Option<u16> {
    let samples = libm::round(period / SAMPLE_TIME);
    let whole = libm::fabs(period / SAMPLE_TIME - samples) < 1e-3;
    // Checked to fit, so the cast is exact.
    (whole && (1.0..=f64::from(u16::MAX)).contains(&samples)).then_some(samples as u16)
}

/// The load ceiling the fastest period keeps under by default.
pub const DEFAULT_CEILING: f64 = 0.7;

/// Seconds between the controller's heartbeats by default (`DriveSettings::heartbeat_period`);
/// validation checks the bus load with it.
pub const HEARTBEAT_PERIOD: f64 = 0.1;

/// Cycles between two temperature queries of one drive by default
/// (`Schedule::temperature_every`); validation checks the bus load with it.
pub const TEMPERATURE_EVERY: u16 = 100;

/// Longest PT segment considered (samples): 655 ms.
const MAX_SAMPLES: u16 = 1820;

/// The streaming traffic of one bus.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoadModel {
    /// Drives on the bus.
    pub drives: usize,
    /// Seconds between the controller's heartbeats.
    pub heartbeat_period: f64,
    /// The schedule.
    pub streaming: Streaming,
    /// Cycles between two temperature queries of one drive (PDO schedule).
    pub temperature_every: u16,
    /// Cycles between two Time Stamps (PDO schedule; 0: none).
    pub time_stamp_every: u16,
}

/// A control period and the load it makes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PeriodLoad {
    /// Drive samples per period (`MP[4]`).
    pub samples: u16,
    /// The period (s).
    pub period: f64,
    /// The fraction of the bus in use, worst-case stuffing.
    pub load: f64,
}

impl LoadModel {
    /// The traffic of `config`'s drives with the controller's heartbeat every
    /// `heartbeat_period` seconds and a temperature query every `temperature_every` cycles.
    pub fn new(config: &RobotConfig, heartbeat_period: f64, temperature_every: u16) -> Self {
        Self {
            drives: config
                .joints
                .iter()
                .filter(|j| j.drive.node_id != 0)
                .count(),
            heartbeat_period,
            streaming: config.drives.streaming,
            temperature_every,
            time_stamp_every: config.drives.time_stamp_every.unwrap_or(TIME_STAMP_EVERY),
        }
    }

    /// Worst-case bits one drive moves in one streaming cycle: with the interpreter schedule
    /// its point and one query, and their answers (every query has the same length); with the
    /// PDO schedule its receive and transmit PDOs.
    pub fn bits_per_drive(&self) -> u32 {
        match self.streaming {
            Streaming::Interpreter => Self::interpreter_bits_per_drive(),
            Streaming::Pdo => pdo_bits_per_drive(),
        }
    }

    /// Worst-case bits of the cycle's frames that are not per drive: the PDO schedule's SYNC,
    /// and its Time Stamp averaged over `time_stamp_every` cycles.
    pub fn bits_per_cycle_shared(&self) -> f64 {
        match self.streaming {
            Streaming::Interpreter => 0.0,
            Streaming::Pdo => {
                let stamps = match self.time_stamp_every {
                    0 => 0.0,
                    every => f64::from(time_stamp_bits()) / f64::from(every),
                };
                f64::from(sync_bits()) + stamps
            }
        }
    }

    /// Worst-case bits per drive and cycle of the queries outside the streaming frames: the
    /// PDO schedule's temperature query and answer, averaged over `temperature_every`.
    pub fn side_query_bits_per_drive(&self) -> f64 {
        match self.streaming {
            Streaming::Interpreter => 0.0,
            Streaming::Pdo => {
                f64::from(temperature_query_bits()) / f64::from(self.temperature_every.max(1))
            }
        }
    }

    /// The interpreter schedule's worst-case bits per drive and cycle.
    fn interpreter_bits_per_drive() -> u32 {
        // Any node: the length of a frame does not depend on its identifier.
        NodeId::new(1).map_or(0, |node| {
            let point = Request::Set {
                command: Mnemonic::QP,
                index: Index::from(1),
                value: Value::Int(0),
            };
            let query = Request::Query {
                command: Mnemonic::PX,
                index: Index::ZERO,
            };
            let answer = |command| Reply::Value {
                command,
                index: Index::ZERO,
                value: Value::Int(0),
            };
            [
                point.to_frame(node),
                answer(Mnemonic::QP).to_frame(node),
                query.to_frame(node),
                answer(Mnemonic::PX).to_frame(node),
            ]
            .iter()
            .map(bits_on_wire)
            .sum()
        })
    }

    /// Worst-case bits of one heartbeat.
    pub fn heartbeat_bits(&self) -> u32 {
        NodeId::new(1).map_or(0, |node| {
            let beat = Heartbeat {
                state: NmtState::Operational,
            };
            bits_on_wire(&beat.to_frame(node))
        })
    }

    /// Worst-case bits per control cycle of `period` seconds, averaged over heartbeats.
    pub fn bits_per_cycle(&self, period: f64) -> f64 {
        let per_drive = f64::from(self.bits_per_drive()) + self.side_query_bits_per_drive();
        let shared = if self.drives > 0 {
            self.bits_per_cycle_shared()
        } else {
            0.0
        };
        let streaming = per_drive * self.drives as f64 + shared;
        let heartbeat = if self.drives > 0 && self.heartbeat_period > 0.0 {
            f64::from(self.heartbeat_bits()) * period / self.heartbeat_period
        } else {
            0.0
        };
        streaming + heartbeat
    }

    /// The fraction of a `bitrate` bus in use with a control period of `period` seconds.
    pub fn load(&self, period: f64, bitrate: u32) -> f64 {
        if period <= 0.0 || bitrate == 0 {
            return f64::INFINITY;
        }
        self.bits_per_cycle(period) / (period * f64::from(bitrate))
    }

    /// The shortest control period — a whole number of 360 µs drive samples, as the PT
    /// segment time must be — whose load stays at or under `ceiling`.
    pub fn fastest_period(&self, bitrate: u32, ceiling: f64) -> Option<PeriodLoad> {
        (1..=MAX_SAMPLES).find_map(|samples| {
            let period = f64::from(samples) * SAMPLE_TIME;
            let load = self.load(period, bitrate);
            (load <= ceiling).then_some(PeriodLoad {
                samples,
                period,
                load,
            })
        })
    }
}

/// Worst-case bits of a SYNC (no data).
fn sync_bits() -> u32 {
    bits_on_wire(&SyncObject.to_frame())
}

/// Worst-case bits of a Time Stamp (4 bytes).
fn time_stamp_bits() -> u32 {
    bits_on_wire(&TimeStamp { micros: 0 }.to_frame())
}

/// Worst-case bits of one drive's PDOs in one cycle: the receive PDO with its PT point (4
/// bytes) and the transmit PDO with its position and PT pointers (8 bytes).
fn pdo_bits_per_drive() -> u32 {
    NodeId::new(1).map_or(0, |node| {
        let point = PtPoint { position: 0 }.to_frame(node);
        let feedback = PtFeedback {
            position: 0,
            head: 0,
            tail: 0,
        };
        bits_on_wire(&point) + bits_on_wire(&feedback.to_frame(node))
    })
}

/// Worst-case bits of a temperature query and its answer.
fn temperature_query_bits() -> u32 {
    NodeId::new(1).map_or(0, |node| {
        let answer = Reply::Value {
            command: Mnemonic::TI,
            index: Index::from(1),
            value: Value::Int(0),
        };
        let query = Request::Query {
            command: Mnemonic::TI,
            index: Index::from(1),
        };
        bits_on_wire(&query.to_frame(node)) + bits_on_wire(&answer.to_frame(node))
    })
}

/// The drives' worst-case streaming load (with the default heartbeat and temperature queries)
/// must stay at or under `drives.max_bus_load` with the chosen schedule, and with the
/// interpreter schedule too if the PDO schedule may fall back to it.
pub(super) fn check(config: &RobotConfig) -> Result<(), ConfigError> {
    let model = LoadModel::new(config, HEARTBEAT_PERIOD, TEMPERATURE_EVERY);
    let mut load = model.load(config.control_period, config.drives.can_bitrate);
    if config.drives.streaming == Streaming::Pdo && config.drives.pdo_fallback {
        let fallback = LoadModel {
            streaming: Streaming::Interpreter,
            ..model
        };
        load = load.max(fallback.load(config.control_period, config.drives.can_bitrate));
    }
    if load <= config.drives.max_bus_load {
        return Ok(());
    }
    // A float-to-integer `as` saturates (and gives 0 for NaN): it cannot fail.
    let percent = libm::ceil(load * 100.0) as u16;
    Err(ConfigError::top(
        "control_period",
        ConfigReason::BusOverloaded { percent },
    ))
}
