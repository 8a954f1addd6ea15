//! The drive manager: the drives' life cycle (spec §6.4), advanced once per control cycle.

//!
//! This file is the life cycle (start, stop, recalibration, the phases of a cycle) and the
//! dispatch to the rest: `start.rs` the start sequence, `interpreter.rs` and `pdo.rs` the two
//! streaming schedules, `receive.rs` the frames received, `outbox.rs` the frames sent.

mod interpreter;
mod outbox;
mod pdo;
mod receive;
mod start;

use armgate_protocol::can::interpreter::{Index, Mnemonic, Request};
use armgate_protocol::can::{Heartbeat, Nmt, NmtState, NodeId, NodeMessage};
use heapless::Vec;

use super::bus::{BusState, CanBus, TxError};
use super::drive::{Drive, Joint};
use super::fault::{BusFault, DriveFault};
use super::link::Link;
use super::settings::{DriveSettings, SetupError, Timing};
use super::startup::{Outgoing, StartStep};
use super::state::{DriveState, Phase};
use super::streaming::{AdaptiveLead, Schedule};
use crate::config::JointUnits;
use outbox::Outbox;

use crate::MAX_JOINTS;
use crate::config::{Streaming, ValidRobot};
use crate::kinematics::Joints;
use crate::motion::Refusal;

/// Received frames handled per call at most; more wait for the next call. A cycle's answers
/// are two per drive, so this is far more than a healthy bus delivers.
const MAX_FRAMES_PER_CALL: usize = 128;

/// The temperature reported for a drive never heard from (spec §6.9): the wire's sentinel.
pub const UNKNOWN_TEMPERATURE: f64 = armgate_protocol::client::UNKNOWN_TEMPERATURE as f64;

/// Why `start` or `stop` was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LifecycleError {
    /// `start`: the drives are already starting, running or stopping.
    Running,
    /// `stop`: the drives are not running.
    NotRunning,
}

/// Counters of what the manager corrected or ignored; nothing here is a fault.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DriveStats {
    /// PT points skipped because a drive fell a segment behind.
    pub points_skipped: u32,
    /// PT points inserted because a drive was about to run a segment ahead.
    pub points_inserted: u32,
    /// Queue-low warnings from the drives.
    pub queue_low_warnings: u32,
    /// Digital Hall emergencies ignored (the seed's whitelist, spec §6.7).
    pub hall_warnings: u32,
    /// Commands refused (wrong length, not finite, beyond the encoder range); the drives held
    /// the previous one.
    pub commands_rejected: u32,
    /// Frames received from unknown nodes or of no interest.
    pub frames_ignored: u32,
    /// Frames with the COB-ID of a kind the manager reads that did not decode as one.
    pub frames_malformed: u32,
    /// Start-step requests sent again because their answer did not come.
    pub requests_repeated: u32,
    /// PDO schedule: PT points the drives' reports showed lost on the bus.
    pub points_lost: u32,
    /// PDO schedule: times the lead was raised by one on every drive (a point inserted on
    /// each), and lowered (a point skipped on each).
    pub lead_raised: u32,
    /// See `lead_raised`.
    pub lead_lowered: u32,
}

/// Runs the servo drives of one arm on one CAN bus: start-up, set-point streaming in
/// position mode, measurement, temperatures, faults and stop.
///
/// Nothing here blocks or reads a clock. The control loop calls, once per control period:
///
/// ```text
/// manager.receive(&mut bus);                        // answers of the last cycle
/// let out = controller.step(now, &manager.measured());
/// manager.transmit(now, out.command.as_ref(), &mut bus);
/// ```
///
/// ([`cycle`](Self::cycle) does both halves, with a measurement one cycle older.) On the
/// interpreter schedule each cycle sends every drive at most two interpreter frames: its PT
/// point and one query (spec §6.5). On the PDO schedule it sends one SYNC and every drive one
/// receive PDO with its PT point; the drives answer the SYNC with their transmit PDOs.
#[derive(Clone, Debug)]
pub struct DriveManager {
    timing: Timing,
    schedule: Schedule,
    ring_len: u16,
    /// PDO schedule: entries of the PT ring.
    pdo_ring_len: u16,
    /// The schedule the robot file asks for.
    configured: Streaming,
    /// The schedule of the current start (the interpreter's after a fallback).
    streaming: Streaming,
    /// A refused PDO mapping falls back to the interpreter schedule.
    may_fall_back: bool,
    /// The refusal that made the current start fall back.
    fallback: Option<DriveFault>,
    /// When the last SYNC went out (s).
    last_sync: Option<f64>,
    /// The last `receive` raised the current fault.
    faulted_in_receive: bool,
    /// PDO schedule: points kept beyond the read pointer at every SYNC.
    pdo_lead: u16,
    /// PDO schedule: SYNCs a transmit PDO may be missing in a row.
    pdo_missing_cycles: u32,
    /// PDO schedule: how far the lead is raised above `pdo_lead` while points are lost (it
    /// outlives a restart: the bus is the same).
    lead_policy: AdaptiveLead,
    joints: Vec<Joint, MAX_JOINTS>,
    phase: Phase,
    fault: Option<DriveFault>,
    /// Cycles since construction (wrapping).
    cycle: u32,
    /// Time of the last heartbeat sent.
    last_heartbeat: Option<f64>,
    /// The last command was `None`: the drives hold.
    holding: bool,
    stats: DriveStats,
}

impl DriveManager {
    /// A manager for `config`'s drives, idle until [`start`](Self::start).
    pub fn new(config: &ValidRobot, settings: &DriveSettings) -> Result<Self, SetupError> {
        let timing = Timing::new(config, settings)?;
        let mut joints = Vec::new();
        for joint in &config.joints {
            let entry = match joint.drive.node_id {
                0 => Joint::Pretend {
                    position: joint.drive.home,
                },
                id => {
                    let node = NodeId::new(id).ok_or(SetupError::BadDrive)?;
                    let units = JointUnits::new(joint).ok_or(SetupError::BadDrive)?;
                    Joint::Real(Drive::new(node, units))
                }
            };
            joints.push(entry).map_err(|_| SetupError::BadDrive)?;
        }
        Ok(Self {
            timing,
            schedule: settings.schedule,
            ring_len: settings.ring_len,
            pdo_ring_len: settings.pdo_ring_len,
            configured: config.drives.streaming,
            streaming: config.drives.streaming,
            may_fall_back: config.drives.pdo_fallback,
            fallback: None,
            last_sync: None,
            faulted_in_receive: false,
            pdo_lead: config.drives.pdo_lead.unwrap_or(settings.pdo_lead),
            pdo_missing_cycles: u32::from(settings.pdo_missing_cycles),
            lead_policy: AdaptiveLead::new(timing.pdo_lead_raise, timing.pdo_lead_quiet),
            joints,
            phase: Phase::Idle,
            fault: None,
            cycle: 0,
            last_heartbeat: None,
            holding: true,
            stats: DriveStats::default(),
        })
    }

    /// Starts the drives (the client's `ON`; the firmware also calls it at power-up, as the
    /// seed auto-started its robot component). Clears the fault. The start runs over the next
    /// cycles; [`is_operational`](Self::is_operational) tells when motion is possible.
    pub fn start(&mut self) -> Result<(), LifecycleError> {
        self.phase = self.phase.start().ok_or(LifecycleError::Running)?;
        self.fault = None;
        self.streaming = self.configured;
        self.fallback = None;
        self.last_sync = None;
        self.lead_policy.restart();
        let first = StartStep::first(self.streaming);
        self.for_each_drive(|drive| {
            drive.link = Link::default();
            drive.reset_steps();
            drive.step = first;
        });
        if !self.has_drives() {
            self.phase = Phase::Streaming(0);
        }
        Ok(())
    }

    /// Puts the joints without a drive at `q`'s values (the rest of `q` is ignored): a
    /// simulation's start pose, which the simulated Whistles take for the driven joints; on a
    /// real arm those joints start at home.
    pub fn place_undriven(&mut self, q: &[f64]) {
        for (joint, &value) in self.joints.iter_mut().zip(q) {
            if let Joint::Pretend { position } = joint
                && value.is_finite()
            {
                *position = value;
            }
        }
    }

    /// Stops the drives (the client's `OF`): they finish the motion already queued, come to
    /// rest on the last commanded position and hold it under servo.
    pub fn stop(&mut self) -> Result<(), LifecycleError> {
        let stopping = self.phase.stop().ok_or(LifecycleError::NotRunning)?;
        self.phase = self.with_hold_cycles(stopping);
        if !self.has_drives() {
            self.phase = Phase::Stopped;
        }
        Ok(())
    }

    /// Declares the current joint positions to be `q` (the client's `RC`, spec §6.8): the
    /// measurement jumps to `q`, the drives do not move. Refused while commands stream (a
    /// command computed before the change would make the arm jump; the seed only advised
    /// using it in mode 0), while starting or stopping, and before every drive's position
    /// has been read.
    pub fn recalibrate(&mut self, q: &[f64]) -> Result<(), Refusal> {
        if q.len() != self.joints.len() {
            return Err(Refusal::WrongJointCount);
        }
        if q.iter().any(|v| !v.is_finite()) {
            return Err(Refusal::InvalidNumber);
        }
        let moving = matches!(self.phase, Phase::Streaming(_)) && !self.holding;
        if moving || matches!(self.state(), DriveState::Starting | DriveState::Stopping) {
            return Err(Refusal::Busy);
        }
        let heard = |joint: &Joint| match joint {
            Joint::Real(drive) => drive.position.is_some(),
            Joint::Pretend { .. } => true,
        };
        if !self.joints.iter().all(heard) {
            return Err(Refusal::NotReady);
        }
        for (joint, &value) in self.joints.iter_mut().zip(q) {
            match joint {
                Joint::Pretend { position } => *position = value,
                Joint::Real(drive) => {
                    if let Some(counts) = drive.position {
                        drive.units = drive.units.recalibrated(counts, value);
                    }
                }
            }
        }
        Ok(())
    }

    /// The receive half of a cycle: takes everything the bus has received and updates the
    /// measurement, temperatures, flow control and faults.
    pub fn receive(&mut self, bus: &mut impl CanBus) {
        let clean = self.fault.is_none();
        self.receive_frames(bus);
        self.faulted_in_receive = clean && self.fault.is_some();
    }

    fn receive_frames(&mut self, bus: &mut impl CanBus) {
        if bus.state() == BusState::BusOff {
            self.raise(DriveFault::Bus(BusFault::BusOff));
        }
        for _ in 0..MAX_FRAMES_PER_CALL {
            let Some(frame) = bus.try_receive() else {
                break;
            };
            self.handle(&frame);
        }
    }

    /// The transmit half of a cycle at time `now` (s): advances the state machine and sends
    /// this cycle's frames. `command` is the controller's joint command; `None` holds the last
    /// one. Commands are taken only while operational.
    pub fn transmit(&mut self, now: f64, command: Option<&Joints>, bus: &mut impl CanBus) {
        self.cycle = self.cycle.wrapping_add(1);
        if bus.state() == BusState::BusOff {
            self.raise(DriveFault::Bus(BusFault::BusOff));
        }
        self.check_links();
        if self.streaming == Streaming::Pdo {
            self.check_pdo(now);
        }
        let mut out = Outbox {
            bus,
            cycle: self.cycle,
            error: None,
        };
        match self.phase {
            Phase::Idle => {}
            Phase::Waking(None) => {
                out.send(&Nmt::START_ALL.to_frame());
                self.phase = Phase::Waking(Some(self.timing.nmt_settle));
            }
            Phase::Waking(Some(left)) if left > 0 => self.phase = Phase::Waking(Some(left - 1)),
            Phase::Waking(Some(_)) => {
                self.phase = Phase::Starting;
                self.start_steps(&mut out);
            }
            Phase::Starting => self.start_steps(&mut out),
            Phase::Streaming(n) => {
                self.accept(command);
                self.stream(now, n, &mut out);
                self.phase = Phase::Streaming(n.wrapping_add(1));
            }
            Phase::Stopping(left) if left > 0 => {
                self.stream(now, self.cycle, &mut out);
                self.phase = Phase::Stopping(left - 1);
            }
            Phase::Stopping(_) => {
                self.halt(&mut out);
                self.phase = if self.fault.is_some() {
                    Phase::Faulted
                } else {
                    Phase::Stopped
                };
            }
            Phase::Stopped | Phase::Faulted => self.poll(&mut out),
        }
        // Last: the controller's transmit FIFO sends in queue order, and the SYNC opens the
        // cycle at its instant.
        self.heartbeat(now, &mut out);
        if let Some(error) = out.error {
            self.raise(DriveFault::Bus(match error {
                TxError::BusOff => BusFault::BusOff,
                TxError::QueueFull => BusFault::QueueFull,
            }));
        }
    }

    /// [`receive`](Self::receive) then [`transmit`](Self::transmit).
    pub fn cycle(&mut self, now: f64, command: Option<&Joints>, bus: &mut impl CanBus) {
        self.receive(bus);
        self.transmit(now, command, bus);
    }

    /// The measured joints: from the drives' last `PX` (the home position before it is
    /// read), the last command for joints without a drive.
    pub fn measured(&self) -> Joints {
        self.per_joint(|joint| match joint {
            Joint::Pretend { position } => *position,
            Joint::Real(drive) => drive.units.position(drive.position.unwrap_or(0)),
        })
    }

    /// The position the drives are commanded to (and, once stopped, hold): the last command
    /// taken, or the start position; the home position for a drive never started.
    pub fn commanded(&self) -> Joints {
        self.per_joint(|joint| match joint {
            Joint::Pretend { position } => *position,
            Joint::Real(drive) => drive.units.position(drive.target.unwrap_or(0)),
        })
    }

    /// Drive temperatures (°C), one per joint; [`UNKNOWN_TEMPERATURE`] for a drive not yet
    /// heard from and for joints without a drive.
    pub fn temperatures(&self) -> Joints {
        self.per_joint(|joint| match joint {
            Joint::Real(Drive {
                temperature: Some(celsius),
                ..
            }) => f64::from(*celsius),
            _ => UNKNOWN_TEMPERATURE,
        })
    }

    /// One value per joint.
    fn per_joint(&self, value: impl Fn(&Joint) -> f64) -> Joints {
        let mut q = Joints::zeros(self.joints.len());
        for (v, joint) in q.iter_mut().zip(&self.joints) {
            *v = value(joint);
        }
        q
    }

    /// What the manager is doing.
    pub fn state(&self) -> DriveState {
        self.phase.state()
    }

    /// The first fault since the last start, if any.
    pub fn fault(&self) -> Option<DriveFault> {
        self.fault
    }

    /// True while set-points stream: the only state in which motion may be commanded.
    pub fn is_operational(&self) -> bool {
        self.state() == DriveState::Operational
    }

    /// What was corrected or ignored so far.
    pub fn stats(&self) -> DriveStats {
        self.stats
    }

    /// PT points joint `joint`'s drive had queued ahead of its read index at its last
    /// read-index answer (interpreter schedule, 3 in steady state) or at the last SYNC
    /// answered (PDO schedule, `DriveSettings::pdo_lead` in steady state); `None` for a joint
    /// without a drive.
    pub fn lead(&self, joint: usize) -> Option<u32> {
        match self.joints.get(joint) {
            Some(Joint::Real(drive)) => drive.stream.as_ref().and_then(|stream| stream.lead()),
            _ => None,
        }
    }

    /// PDO schedule: the lead the stream keeps at every SYNC now, `drives.pdo_lead` or more
    /// while points are being lost (one less on a drive whose segment boundary precedes the
    /// SYNC).
    pub fn pdo_lead_now(&self) -> u16 {
        self.pdo_lead.saturating_add(self.lead_policy.raised())
    }

    /// The schedule of the current start: the robot file's, or the interpreter's after a
    /// fallback.
    pub fn streaming(&self) -> Streaming {
        self.streaming
    }

    /// The mapping refusal that made the current start fall back to the interpreter
    /// schedule (`drives.pdo_fallback`), if any: reported as a warning, not a fault.
    pub fn fallback(&self) -> Option<DriveFault> {
        self.fallback
    }

    fn has_drives(&self) -> bool {
        self.joints.iter().any(|j| matches!(j, Joint::Real(_)))
    }

    fn for_each_drive(&mut self, mut f: impl FnMut(&mut Drive)) {
        for joint in self.joints.iter_mut() {
            if let Joint::Real(drive) = joint {
                f(drive);
            }
        }
    }

    /// Records `fault` (the first one since the start wins) and stops.
    fn raise(&mut self, fault: DriveFault) {
        self.fault.get_or_insert(fault);
        let can_send = !matches!(fault, DriveFault::Bus(_));
        let next = self.phase.fault(can_send);
        self.phase = match self.phase {
            Phase::Stopping(_) => next,
            _ => self.with_hold_cycles(next),
        };
    }

    /// Faults the first drive that has left a request unanswered too long.
    fn check_links(&mut self) {
        let (cycle, timeout) = (self.cycle, self.timing.reply_timeout);
        let silent = self.joints.iter().position(
            |joint| matches!(joint, Joint::Real(drive) if drive.link.silent(cycle, timeout)),
        );
        if let Some(joint) = silent {
            self.raise(DriveFault::NotAnswering { joint });
        }
    }

    /// Sends the controller's heartbeat when due (from the first start on).
    fn heartbeat<B: CanBus>(&mut self, now: f64, out: &mut Outbox<'_, B>) {
        let period = self.timing.heartbeat_period;
        let due = self.last_heartbeat.is_none_or(|last| now - last >= period);
        if self.phase == Phase::Idle || !self.has_drives() || !due {
            return;
        }
        let beat = Heartbeat {
            state: NmtState::Operational,
        };
        out.send(&beat.to_frame(self.timing.controller));
        // Keep the average period exact, but do not try to catch up after a long gap.
        self.last_heartbeat = Some(match self.last_heartbeat {
            Some(last) if now - last < 2.0 * period => last + period,
            _ => now,
        });
    }

    /// Takes a command, all joints or none: each drive's target and each pretend joint's
    /// position.
    fn accept(&mut self, command: Option<&Joints>) {
        self.holding = command.is_none();
        let Some(q) = command else { return };
        let mut counts: Vec<Option<i32>, MAX_JOINTS> = Vec::new();
        let mut valid = q.len() == self.joints.len();
        for (joint, &value) in self.joints.iter().zip(q.iter()) {
            let converted = match joint {
                Joint::Pretend { .. } => value.is_finite().then_some(None),
                Joint::Real(drive) => drive.units.counts(value).map(Some),
            };
            valid &= converted.is_some();
            let _ = counts.push(converted.flatten());
        }
        if !valid {
            self.stats.commands_rejected = self.stats.commands_rejected.saturating_add(1);
            return;
        }
        // `&counts`: dropping heapless's by-value iterator has a panic path.
        for ((joint, &value), &counts) in self.joints.iter_mut().zip(q.iter()).zip(&counts) {
            match joint {
                Joint::Pretend { position } => *position = value,
                Joint::Real(drive) => drive.target = counts,
            }
        }
    }

    /// One streaming cycle on the schedule of this start (`streamed`: the cycle count the
    /// query schedule staggers by).
    fn stream<B: CanBus>(&mut self, now: f64, streamed: u32, out: &mut Outbox<'_, B>) {
        match self.streaming {
            Streaming::Interpreter => self.stream_interpreter(streamed, out),
            Streaming::Pdo => {
                self.last_sync = Some(now);
                self.stream_pdo(now, streamed, out);
            }
        }
    }

    /// The end of a stop: `ST` to every drive, which then holds where its profile ended.
    /// The motors stay on (as in the seed, spec §6.4): an arm under gravity must not go limp.
    fn halt<B: CanBus>(&mut self, out: &mut Outbox<'_, B>) {
        let stop = Outgoing::Interpreter(Request::Query {
            command: Mnemonic::ST,
            index: Index::ZERO,
        });
        self.for_each_drive(|drive| {
            out.request(drive, &stop);
            drive.reset_steps();
        });
    }

    /// Stopped or faulted: the position (or now and then the temperature) of every drive.
    fn poll<B: CanBus>(&mut self, out: &mut Outbox<'_, B>) {
        let (schedule, cycle) = (self.schedule, self.cycle);
        for (index, joint) in self.joints.iter_mut().enumerate() {
            if let Joint::Real(drive) = joint {
                let query = schedule.query(cycle, index, false);
                out.request(drive, &Outgoing::Interpreter(query.request()));
            }
        }
    }
}
