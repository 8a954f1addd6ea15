//! A simulated Elmo Whistle on the CAN bus, so the firmware and the tests can run without an
//! arm.
//!
//! It answers what the drive manager uses — NMT, the consumer-heartbeat SDO (0x1016), and the
//! binary interpreter commands `UM`, `MO`, `PX`, `VX`, `PT`, `MP[1..=6]`, `QP[k]`, `TI[1]`,
//! `BG`, `ST` — runs PT motion through its table ([`pt_table`]), moves a speed-limited,
//! lagging motor ([`servo`]), watches the controller's heartbeat, and sends the emergencies a
//! real drive would. For the PDO streaming schedule it also has RPDO3 and TPDO3 and a group id
//! in its object dictionary ([`pdo`]), mapped by SDO: an RPDO3 point goes into the PT table at
//! the write pointer, and after every SYNC a synchronous TPDO3 reports the position and the PT
//! pointers sampled when the SYNC arrived. Its interpreter runs one command at a time and queues one more: a third
//! command arriving meanwhile replaces the queued one, which is lost (what the thesis observed,
//! spec §6.5), and the drive reports it with an emergency. [`WhistleFaults`] injects faults.
//!
//! Time is in nanoseconds on the bus's clock; the drive samples its position loop every
//! 360 µs of its own clock, which may run fast or slow by a few ppm, unless SYNC and Time
//! Stamp pairs lock it to the controller's ([`motion_clock`]).

mod interpreter;
pub mod motion_clock;
pub mod pdo;
mod process_data;
pub mod pt_table;
pub mod servo;

use armgate_protocol::can::interpreter::{Mnemonic, Reply, Request, Value};
use armgate_protocol::can::{
    CanFrame, ConsumerHeartbeat, Emcy, Function, Heartbeat, Nmt, NmtCommand, NmtState, NodeId,
    NodeMessage, Object, SYNC_ID, SYNCHRONOUS, SdoRequest, SdoResponse, SdoValue, SyncObject,
    TIME_STAMP_ID, TimeStamp, sdo_abort,
};
use heapless::Deque;

use self::motion_clock::MotionClock;
use self::pdo::{PdoObjects, RpdoContent, Sampled, tpdo_payload};
use self::pt_table::{Latency, PtTable, PushError, WriteError};
use self::servo::Servo;
use crate::config::JointConfig;
use crate::config::SAMPLE_TIME;
use crate::drives::{DriveEmergency, JointUnits, POSITION_MODE, REASON_UNDERFLOW};

/// Frames a drive can have waiting to be sent.
const TX_QUEUE: usize = 16;
/// PT points received by RPDO and waiting for the next sample.
const RX_POINTS: usize = 4;
/// Internal events handled per `advance_to` call at most (a call normally covers a few
/// samples).
const MAX_EVENTS: u32 = 1_000_000;
/// CiA 301 EMCY: PDO not processed due to length error.
const PDO_LENGTH_ERROR: u16 = 0x8210;
/// Error register bits 0 (generic) and 4 (communication).
const COMMUNICATION_REGISTER: u8 = 0x11;

/// Error codes the simulated interpreter answers with. They are the simulation's own; a real
/// drive's are listed under `EC` in the SimplIQ command reference.
pub mod error_code {
    /// Unknown command.
    pub const BAD_COMMAND: u8 = 2;
    /// Array index out of range.
    pub const BAD_INDEX: u8 = 3;
    /// The command cannot be assigned, or queried.
    pub const BAD_ACCESS: u8 = 7;
    /// A value out of range.
    pub const BAD_VALUE: u8 = 21;
    /// Not allowed with the motor on (`UM`).
    pub const MOTOR_ON: u8 = 57;
    /// Not allowed with the motor off (`BG`).
    pub const MOTOR_OFF: u8 = 58;
    /// `BG` without a valid PT set-up.
    pub const BAD_SETUP: u8 = 60;
    /// Injected: [`WhistleFaults::error_on`](super::WhistleFaults::error_on).
    pub const INJECTED: u8 = 99;
}

/// A simulated drive's parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WhistleConfig {
    /// Its node id.
    pub node: NodeId,
    /// Its joint's units (for the speed limit in joint units).
    pub units: JointUnits,
    /// Speed limit (rad/s or m/s): the robot file's `drive.max_speed` (by default 0.9, as the
    /// thesis observed).
    pub max_speed: f64,
    /// Time constant of the position loop's lag (s).
    pub lag: f64,
    /// Time the interpreter takes per command (s).
    pub interpreter_time: f64,
    /// How fast the drive's oscillator runs (ppm; positive = fast), before any lock.
    pub clock_error_ppm: f64,
    /// Where the drive's first sample falls (s, within one sample time).
    pub sample_phase: f64,
    /// The unit mode at power-up.
    pub unit_mode: i32,
    /// The encoder counts at power-up.
    pub counts: i32,
    /// Ambient temperature (°C).
    pub ambient: f64,
    /// Time from a SYNC's end to its synchronous TPDO being ready to send (s). ASSUMED: the
    /// manual gives no figure.
    pub sync_response: f64,
    /// The PT motion fetches one point further than the manual says (`QP[r+2]` when segment
    /// `r` starts, the previous model): a drive that needs one point more of lead.
    pub reads_ahead: bool,
}

impl WhistleConfig {
    /// The drive of `joint` with the default behaviour, or `None` for a joint without one.
    pub fn for_joint(joint: &JointConfig) -> Option<Self> {
        let node = NodeId::new(joint.drive.node_id)?;
        Some(Self {
            node,
            units: JointUnits::new(joint)?,
            max_speed: joint.drive.max_speed,
            lag: 0.004,
            interpreter_time: 250e-6,
            clock_error_ppm: 0.0,
            // Spread the drives' sample instants a little, as independent clocks would be.
            sample_phase: f64::from(node.get() % 9) * SAMPLE_TIME / 9.0,
            unit_mode: POSITION_MODE,
            counts: 0,
            ambient: 25.0,
            sync_response: 50e-6,
            reads_ahead: false,
        })
    }
}

/// Faults to inject; the default injects none.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WhistleFaults {
    /// The drive sends nothing at all (it still receives and moves).
    pub silent: bool,
    /// Every n-th interpreter reply is lost (0: none).
    pub drop_every_reply: u32,
    /// Every n-th interpreter command received is lost (0: none).
    pub drop_every_command: u32,
    /// Extra delay of every reply (s).
    pub reply_delay: f64,
    /// This command is answered with the error bit.
    pub error_on: Option<Mnemonic>,
    /// PT motion stops advancing, without notice.
    pub stall: bool,
    /// `UM=` is echoed but does not change the unit mode.
    pub stuck_unit_mode: bool,
    /// SDO writes to this object are aborted with 0x0604_0041 ("cannot be mapped"): a drive
    /// whose firmware refuses the PDO mapping.
    pub refuse_object: Option<Object>,
    /// The synchronous TPDOs of this many SYNCs are not sent (counted down; `u32::MAX`: none
    /// are sent, for ever).
    pub skip_tpdos: u32,
}

/// What happened to a simulated drive.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WhistleStats {
    /// Interpreter commands lost because two were already waiting, and RPDO points lost
    /// because four were waiting for the next sample.
    pub commands_lost: u32,
    /// PT motions ended by a buffer underflow.
    pub underflows: u32,
    /// QP writes refused because the entry was not yet executed.
    pub overflows: u32,
    /// Consumer heartbeat timeouts.
    pub heartbeat_timeouts: u32,
    /// Frames that did not fit the transmit queue.
    pub transmit_overruns: u32,
    /// When PT motion last began (ns on the bus clock).
    pub begun_at: Option<u64>,
    /// The first sample of the last PT motion (ns on the bus clock): when its profile started
    /// to move. The spread over the drives is the start skew.
    pub started_at: Option<u64>,
    /// SYNCs received while operational.
    pub syncs: u32,
    /// Synchronous TPDOs sent.
    pub tpdos_sent: u32,
    /// Synchronous TPDOs not sent ([`WhistleFaults::skip_tpdos`]).
    pub tpdos_skipped: u32,
    /// PT points received by RPDO and written.
    pub pdo_points: u32,
    /// RPDO points refused: write pointer out of range, PDO not mapped, too short.
    pub pdo_errors: u32,
    /// Write-to-reach times of the PT points.
    pub latency: Latency,
}

/// A simulated Whistle.
#[derive(Clone, Debug)]
pub struct SimWhistle {
    config: WhistleConfig,
    /// Nanoseconds per sample on the bus clock.
    sample_ns: f64,
    /// Where sample counting restarted (sample, ns) after a clock change.
    epoch: (u64, f64),
    /// The motion clock and its lock to the controller's.
    clock: MotionClock,
    /// Samples done since power-up.
    samples: u64,
    /// The time of the last event handled (ns).
    now: u64,
    nmt: NmtState,
    unit_mode: i32,
    motor_on: bool,
    table: PtTable,
    servo: Servo,
    /// The position the servo follows (counts).
    reference: f64,
    /// The command running and when it completes.
    running: Option<(Request, u64)>,
    /// The command waiting.
    waiting: Option<Request>,
    /// The producer and timeout (ns) of the consumer heartbeat.
    consumer: Option<(NodeId, u64)>,
    /// When the watched heartbeat was last heard (ns); `None` until the first one.
    last_beat: Option<u64>,
    commands_received: u32,
    replies_made: u32,
    tx: Deque<(CanFrame, u64), TX_QUEUE>,
    /// RPDO3, TPDO3 and the group id.
    pdo: PdoObjects,
    /// The group id in effect: RPDO2 frames to it are this drive's too.
    group: Option<NodeId>,
    /// A point from a synchronous RPDO, applied at the next SYNC.
    deferred_point: Option<i32>,
    /// Points received by RPDO, written at the next sample.
    received_points: Deque<i32, RX_POINTS>,
    stats: WhistleStats,
    /// Faults being injected.
    pub faults: WhistleFaults,
}

impl SimWhistle {
    /// A drive at power-up: pre-operational, motor off, at `config.counts`.
    pub fn new(config: WhistleConfig) -> Self {
        let sample_ns = sample_ns(config.clock_error_ppm);
        let dt = sample_ns * 1e-9;
        let max_speed = config
            .units
            .counts_per_second(config.max_speed)
            .map_or(f64::MAX, f64::from);
        let position = f64::from(config.counts);
        Self {
            config,
            sample_ns,
            epoch: (0, config.sample_phase * 1e9),
            clock: MotionClock::default(),
            samples: 0,
            now: 0,
            nmt: NmtState::PreOperational,
            unit_mode: config.unit_mode,
            motor_on: false,
            table: PtTable::new(config.reads_ahead),
            servo: Servo::new(position, max_speed, config.lag, dt, config.ambient),
            reference: position,
            running: None,
            waiting: None,
            consumer: None,
            last_beat: None,
            commands_received: 0,
            replies_made: 0,
            tx: Deque::new(),
            pdo: PdoObjects::new(config.node),
            group: None,
            deferred_point: None,
            received_points: Deque::new(),
            stats: WhistleStats::default(),
            faults: WhistleFaults::default(),
        }
    }

    /// Its node id.
    pub fn node(&self) -> NodeId {
        self.config.node
    }

    /// The motor position (counts, rounded as `PX` reports it).
    pub fn position(&self) -> i32 {
        round_i32(self.servo.position())
    }

    /// The position the motor is told to follow (counts): the PT profile, held where it
    /// ended.
    pub fn profile(&self) -> f64 {
        self.reference
    }

    /// The motor position in joint units (rad or m), from the rounded counts.
    pub fn joint_position(&self) -> f64 {
        self.config.units.position(self.position())
    }

    /// True while PT motion runs.
    pub fn pt_running(&self) -> bool {
        self.table.running()
    }

    /// Its NMT state.
    pub fn nmt_state(&self) -> NmtState {
        self.nmt
    }

    /// The PT table.
    pub fn table(&self) -> &PtTable {
        &self.table
    }

    /// RPDO3, TPDO3 and the group id as configured by SDO.
    pub fn pdo_objects(&self) -> &PdoObjects {
        &self.pdo
    }

    /// The group id in effect (0x2040 as of the last reset communication).
    pub fn group(&self) -> Option<NodeId> {
        self.group
    }

    /// How fast the drive's oscillator runs (ppm; positive = fast), before any lock.
    pub fn clock_error_ppm(&self) -> f64 {
        self.config.clock_error_ppm
    }

    /// Makes the drive's oscillator run `ppm` fast (negative: slow) from now on.
    pub fn set_clock_error_ppm(&mut self, ppm: f64) {
        self.config.clock_error_ppm = ppm;
        self.retime();
    }

    /// The motion clock: the lock's correction and the pairs it took.
    pub fn motion_clock(&self) -> &MotionClock {
        &self.clock
    }

    /// Samples on at the oscillator's rate with the lock's correction. The part of the sample
    /// under way stays done: the clock is continuous and the next sample never falls before
    /// now.
    fn retime(&mut self) {
        // Before the first sample (power-up) the sample phase stands.
        let last = self.sample_ns_at(self.samples);
        let now = (self.now as f64).max(last);
        let done = ((now - last) / self.sample_ns).min(1.0);
        self.sample_ns = sample_ns(self.config.clock_error_ppm + self.clock.correction_ppm());
        self.epoch = (self.samples, now - done * self.sample_ns);
    }

    /// The motion clock's oscillator count now (µs): 360 µs a sample, fractions included.
    fn oscillator_us(&self) -> f64 {
        self.samples_at(self.now as f64) * SAMPLE_TIME * 1e6
    }

    /// What happened so far.
    pub fn stats(&self) -> WhistleStats {
        WhistleStats {
            begun_at: self.table.begun_at(),
            started_at: self.table.started_at(),
            latency: self.table.latency(),
            ..self.stats
        }
    }

    /// Forgets the counters and latencies so far.
    pub fn reset_stats(&mut self) {
        self.stats = WhistleStats::default();
        self.table.reset_latency();
    }

    /// Sends `emergency` now (an injected fault).
    pub fn inject(&mut self, emergency: DriveEmergency) {
        self.emit(emergency.encode().to_frame(self.config.node), self.now);
    }

    /// The time of the drive's next internal event (ns): a sample, or a command completing.
    pub fn next_event(&self) -> u64 {
        let sample = self.sample_time(self.samples + 1);
        self.running.map_or(sample, |(_, done)| done.min(sample))
    }

    /// The bus-clock time of sample `k` (ns).
    fn sample_time(&self, k: u64) -> u64 {
        self.sample_ns_at(k).max(0.0) as u64
    }

    /// The same, unrounded.
    fn sample_ns_at(&self, k: u64) -> f64 {
        let (sample, at) = self.epoch;
        at + (k as f64 - sample as f64) * self.sample_ns
    }

    /// Samples counted at bus time `t` (ns), fractions included: the inverse of
    /// [`Self::sample_ns_at`].
    fn samples_at(&self, t: f64) -> f64 {
        let (sample, at) = self.epoch;
        sample as f64 + (t - at) / self.sample_ns
    }

    /// Runs the drive up to time `t` (ns).
    pub fn advance_to(&mut self, t: u64) {
        for _ in 0..MAX_EVENTS {
            let next = self.next_event();
            if next > t {
                break;
            }
            self.now = next;
            match self.running {
                Some((request, done)) if done == next => self.complete(request),
                _ => self.sample(),
            }
        }
        self.now = self.now.max(t);
    }

    /// The next frame to send and the time it is ready (ns), if any.
    pub fn pop_transmit(&mut self) -> Option<(CanFrame, u64)> {
        self.tx.pop_front()
    }

    /// Takes a frame from the bus at the current time.
    pub fn receive(&mut self, frame: &CanFrame) {
        let node = self.config.node;
        if let Ok(nmt) = Nmt::parse(frame) {
            if nmt.node.is_none_or(|n| n == node) {
                self.nmt_command(nmt.command);
            }
            return;
        }
        if frame.id() == SYNC_ID {
            if SyncObject::parse(frame).is_ok() && self.nmt != NmtState::Stopped {
                // SYNC and Time Stamp are served in pre-operational too (CiA 301).
                self.clock.latch(self.oscillator_us());
                if self.nmt == NmtState::Operational {
                    self.sync();
                }
            }
            return;
        }
        if frame.id() == TIME_STAMP_ID {
            let stamp = TimeStamp::parse(frame)
                .ok()
                .filter(|_| self.nmt != NmtState::Stopped);
            if let Some(stamp) = stamp
                && self.clock.stamp(stamp.micros).is_some()
            {
                self.retime();
            }
            return;
        }
        if frame.id() == self.pdo.rpdo3.id()
            && self.pdo.rpdo3.valid()
            && self.nmt == NmtState::Operational
        {
            self.rpdo3(frame);
            return;
        }
        match Function::split(frame.id()) {
            Ok((Function::Rpdo2, to)) if to == node || Some(to) == self.group => {
                if let (Ok((_, request)), NmtState::Operational) = (Request::parse(frame), self.nmt)
                {
                    self.command(request);
                }
            }
            Ok((Function::SdoRequest, to)) if to == node && self.nmt != NmtState::Stopped => {
                if let Ok((_, request)) = SdoRequest::parse(frame) {
                    self.sdo(request);
                }
            }
            Ok((Function::Heartbeat, from)) => {
                let watched = self.consumer.is_some_and(|(producer, _)| producer == from);
                if watched && Heartbeat::parse(frame).is_ok() {
                    self.last_beat = Some(self.now);
                }
            }
            _ => {}
        }
    }

    fn nmt_command(&mut self, command: NmtCommand) {
        match command {
            NmtCommand::Start => self.nmt = NmtState::Operational,
            NmtCommand::Stop => self.nmt = NmtState::Stopped,
            NmtCommand::EnterPreOperational => self.nmt = NmtState::PreOperational,
            NmtCommand::ResetNode | NmtCommand::ResetCommunication => {
                // The communication objects return to their power-on values; the group id
                // written to 0x2040 takes effect (MAN-CAN301IG §13).
                let group = self.pdo.group_written;
                self.pdo = PdoObjects {
                    group_written: group,
                    ..PdoObjects::new(self.config.node)
                };
                self.group = NodeId::new(group);
                self.deferred_point = None;
                self.received_points.clear();
                self.table = PtTable::new(self.config.reads_ahead);
                self.motor_on = false;
                self.consumer = None;
                self.last_beat = None;
                self.running = None;
                self.waiting = None;
                self.nmt = NmtState::PreOperational;
                let boot = Heartbeat {
                    state: NmtState::BootUp,
                };
                self.emit(boot.to_frame(self.config.node), self.now);
            }
        }
    }

    /// One position-loop sample: heartbeat watch, PT motion, motor.
    fn sample(&mut self) {
        self.samples += 1;
        let dt = self.sample_ns * 1e-9;
        let timed_out = match (self.consumer, self.last_beat) {
            (Some((_, timeout)), Some(last)) => self.now.saturating_sub(last) > timeout,
            _ => false,
        };
        if timed_out {
            // CiA 301 default reaction (object 0x1029): pre-operational; the drive stops its
            // motion and holds where it is.
            self.stats.heartbeat_timeouts += 1;
            self.last_beat = None;
            self.table.stop();
            self.nmt = NmtState::PreOperational;
            self.inject(DriveEmergency::HeartbeatLost);
        }
        for _ in 0..RX_POINTS {
            let Some(point) = self.received_points.pop_front() else {
                break;
            };
            self.write_point(point);
        }
        let sample = self.table.sample(self.now, self.faults.stall);
        if let Some(reference) = sample.reference {
            self.reference = reference;
        }
        if let Some(emergency) = sample.emergency {
            if let DriveEmergency::MotionTerminated {
                reason: REASON_UNDERFLOW,
                ..
            } = emergency
            {
                self.stats.underflows += 1;
            }
            self.inject(emergency);
        }
        self.servo
            .sample(self.motor_on.then_some(self.reference), dt);
    }

    /// Queues `frame` for sending at `ready` (ns), unless the drive is silent.
    fn emit(&mut self, frame: CanFrame, ready: u64) {
        if self.faults.silent {
            return;
        }
        if self.tx.push_back((frame, ready)).is_err() {
            self.stats.transmit_overruns += 1;
        }
    }
}

/// Nanoseconds of bus time per sample of a clock `ppm` fast: a fast clock counts its 360 µs
/// sooner.
fn sample_ns(ppm: f64) -> f64 {
    SAMPLE_TIME * 1e9 / (1.0 + ppm * 1e-6)
}

/// True if `count` is a multiple of `every` (never for `every` = 0).
fn nth(count: u32, every: u32) -> bool {
    every != 0 && count.is_multiple_of(every)
}

/// Seconds to nanoseconds (0 for negative or NaN).
fn seconds_to_ns(seconds: f64) -> u64 {
    libm::round(seconds * 1e9).max(0.0) as u64
}

/// `value` rounded to an `i32`, saturating.
fn round_i32(value: f64) -> i32 {
    libm::round(value).clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32
}
