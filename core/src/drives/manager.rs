//! The drive manager: the drives' life cycle (spec §6.4), advanced once per control cycle.

use armgate_protocol::can::interpreter::{Index, Mnemonic, Reply, Request, Value};
use armgate_protocol::can::{
    CanFrame, Heartbeat, Incoming, MappingRefusal, Nmt, NmtCommand, NmtState, NodeId, NodeMessage,
    SdoResponse,
};
use heapless::Vec;

use super::bus::{BusState, CanBus, TxError};
use super::drive::{Drive, Joint};
use super::emergency::{DriveEmergency, REASON_UNDERFLOW};
use super::fault::{BusFault, DriveFault};
use super::link::Link;
use super::settings::{DriveSettings, SetupError, Timing};
use super::startup::{Outgoing, StartStep, StepContext};
use super::state::{DriveState, Phase};
use super::streaming::{
    AdaptiveLead, FILLED_POINTS, FlowError, PdoStream, PtStream, Query, Schedule,
};
use super::units::JointUnits;
mod pdo;

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
        let pdo = self.streaming == Streaming::Pdo;
        self.for_each_drive(|drive| {
            drive.link = Link::default();
            drive.reset_steps();
            if pdo {
                drive.step = StartStep::GroupId;
            }
        });
        if !self.has_drives() {
            self.phase = Phase::Streaming(0);
        }
        Ok(())
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
            if matches!(self.phase, Phase::Streaming(_) | Phase::Stopping(_)) {
                self.check_sync(now);
            }
            if matches!(self.phase, Phase::Streaming(_)) {
                self.check_feedback();
            }
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
                self.stream_any(now, n, &mut out);
                self.phase = Phase::Streaming(n.wrapping_add(1));
            }
            Phase::Stopping(left) if left > 0 => {
                self.stream_any(now, self.cycle, &mut out);
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
            Some(Joint::Real(drive)) => match (&drive.stream, &drive.pdo) {
                (Some(stream), _) => stream.lead(),
                (_, Some(pdo)) => pdo.lead(),
                _ => None,
            },
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

    /// One cycle of the start sequence: each drive advances when its step is answered and
    /// sends the next step's frames; when every drive is ready, all get `BG` in one cycle.
    fn start_steps<B: CanBus>(&mut self, out: &mut Outbox<'_, B>) {
        let (pdo, pdo_lead) = (self.streaming == Streaming::Pdo, self.pdo_lead_now());
        let timing = self.timing;
        // One point more than the lead, and at least FILLED_POINTS: the first point streamed
        // after `BG` is then due at the second segment start, not the first.
        let (ring_len, filled) = if pdo {
            (
                self.pdo_ring_len,
                pdo_lead.saturating_add(1).max(FILLED_POINTS),
            )
        } else {
            (self.ring_len, FILLED_POINTS)
        };
        let context = |drive: &Drive| StepContext {
            controller: timing.controller,
            heartbeat_timeout_ms: timing.heartbeat_timeout_ms,
            ring_len,
            samples_per_point: timing.samples_per_point,
            position: drive.target,
            filled,
            node: drive.node,
            group: timing.group,
        };
        let mut fault = None;
        for (index, joint) in self.joints.iter_mut().enumerate() {
            let Joint::Real(drive) = joint else { continue };
            let answered = drive.step_sent && drive.awaiting.is_empty();
            let position_known = drive.step != StartStep::ReadPosition || drive.position.is_some();
            if answered && position_known {
                match drive
                    .step
                    .next(drive.unit_mode, timing.unit_mode_settle, pdo, filled)
                {
                    Ok(next) => {
                        if next == StartStep::Configure(0) {
                            drive.target = drive.position;
                        }
                        drive.step = next;
                        drive.step_sent = false;
                    }
                    Err(found) => {
                        fault.get_or_insert(DriveFault::WrongUnitMode {
                            joint: index,
                            found,
                        });
                    }
                }
            }
            if !drive.step_sent {
                let ctx = context(drive);
                send_step(drive, &ctx, out);
            } else if !drive.awaiting.is_empty() && drive.retry.due(out.cycle, timing.reply_timeout)
            {
                let ctx = context(drive);
                resend_step(drive, &ctx, out);
                self.stats.requests_repeated = self.stats.requests_repeated.saturating_add(1);
                self.lead_policy.saw_loss();
            }
        }
        if let Some(fault) = fault {
            self.raise(fault);
            return;
        }
        self.regroup(out);
        let ready = |joint: &Joint| match joint {
            Joint::Real(drive) => drive.step == StartStep::Ready && drive.target.is_some(),
            Joint::Pretend { .. } => true,
        };
        if self.joints.iter().all(ready) {
            if pdo {
                // One `BG` to the group: every drive begins at once, and answers it.
                let begin = Request::Query {
                    command: Mnemonic::BG,
                    index: Index::ZERO,
                };
                out.send(&begin.to_frame(timing.group));
            }
            // A request repeated in this start (its answer lost) is the bus losing frames
            // before any point is streamed: the streams begin `START_RAISE` points higher,
            // instead of learning it from the first lost point, which at the least lead
            // underflows its drive before any report can show it. The ring was filled for the
            // lower lead; the streams make up the points in their first cycles.
            self.lead_policy.restart();
            let pdo_lead = self.pdo_lead_now();
            let cycle = out.cycle;
            self.for_each_drive(|drive| {
                if let Some(position) = drive.target {
                    if pdo {
                        let stream = PdoStream::new(ring_len, pdo_lead, filled, position);
                        drive.pdo = Some(stream);
                    } else {
                        drive.stream = Some(PtStream::new(ring_len, position));
                    }
                    drive.step = StartStep::Begin;
                    let ctx = context(drive);
                    if pdo {
                        // The group `BG` went out: each drive owes its answer.
                        drive.awaiting.clear();
                        for frame in &drive.step.frames(&ctx) {
                            let _ = drive.awaiting.push(*frame);
                            drive.link.sent(cycle);
                        }
                        drive.step_sent = true;
                    } else {
                        send_step(drive, &ctx, out);
                    }
                }
            });
            self.phase = Phase::Streaming(0);
        }
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

    /// One streaming cycle on the schedule of this start.
    fn stream_any<B: CanBus>(&mut self, now: f64, streamed: u32, out: &mut Outbox<'_, B>) {
        match self.streaming {
            Streaming::Interpreter => self.stream(streamed, out),
            Streaming::Pdo => {
                self.last_sync = Some(now);
                self.stream_pdo(now, streamed, out);
            }
        }
    }

    /// One streaming cycle (`streamed`: the cycle count the schedule staggers by): every
    /// running drive gets its point(s) towards its target and one query; drives not yet
    /// running (a stop during the start) only the query.
    fn stream<B: CanBus>(&mut self, streamed: u32, out: &mut Outbox<'_, B>) {
        let schedule = self.schedule;
        let stats = &mut self.stats;
        for (index, joint) in self.joints.iter_mut().enumerate() {
            let Joint::Real(drive) = joint else { continue };
            let points = match (drive.target, drive.stream.as_mut()) {
                (Some(target), Some(stream)) => stream.points(target),
                _ => Vec::new(),
            };
            for &(slot, value) in &points {
                let point = Request::Set {
                    command: Mnemonic::QP,
                    index: slot,
                    value: Value::Int(value),
                };
                out.request(drive, &Outgoing::Interpreter(point));
            }
            match points.len() {
                0 if drive.stream.is_some() => {
                    stats.points_skipped = stats.points_skipped.saturating_add(1);
                }
                2 => {
                    stats.points_inserted = stats.points_inserted.saturating_add(1);
                    continue; // two frames already: no query this cycle
                }
                _ => {}
            }
            let pacing = points.len() == 1;
            let query = schedule.query(streamed, index, pacing);
            out.request(drive, &Outgoing::Interpreter(query.request()));
            if let (Query::ReadIndex, Some(stream)) = (query, drive.stream.as_mut()) {
                stream.asked();
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

    /// One received frame. Its sender is its own COB-ID's node (the seed kept the previous
    /// frame's sender for unknown nodes and gave up on the cycle at an unknown SDO, spec §9
    /// item 33).
    fn handle(&mut self, frame: &CanFrame) {
        match Incoming::classify(frame) {
            Incoming::Interpreter { node, reply } => self.on_reply(node, reply),
            Incoming::Emcy { node, emcy } => self.on_emergency(node, DriveEmergency::decode(&emcy)),
            Incoming::SdoResponse { node, response } => self.on_sdo(node, response),
            Incoming::Feedback { node, feedback } => self.on_feedback(node, feedback),
            Incoming::Heartbeat { .. }
            | Incoming::Sync
            | Incoming::Malformed { .. }
            | Incoming::Other => {
                self.ignored();
            }
        }
    }

    fn ignored(&mut self) {
        self.stats.frames_ignored = self.stats.frames_ignored.saturating_add(1);
    }

    /// The joint and drive of `node`.
    fn drive_mut(&mut self, node: NodeId) -> Option<(usize, &mut Drive)> {
        self.joints
            .iter_mut()
            .enumerate()
            .find_map(|(index, joint)| match joint {
                Joint::Real(drive) if drive.node == node => Some((index, drive)),
                _ => None,
            })
    }

    fn on_reply(&mut self, node: NodeId, reply: Reply) {
        let cycle = self.cycle;
        let Some((joint, drive)) = self.drive_mut(node) else {
            self.ignored();
            return;
        };
        drive.link.heard(cycle);
        let fault = match reply {
            Reply::Error { command, code, .. } => Some(DriveFault::ErrorReply {
                joint,
                command,
                code,
            }),
            Reply::Value {
                command,
                index,
                value,
            } => {
                if let Some(at) = drive
                    .awaiting
                    .iter()
                    .position(|frame| frame.answered_by(command, index))
                {
                    drive.awaiting.swap_remove(at);
                }
                // Every command used here answers an integer; the seed read floats only for
                // TC and IQ, which position mode does not use.
                let value = match value {
                    Value::Int(v) => v,
                    Value::Float(_) => return,
                };
                match command {
                    Mnemonic::PX => drive.position = Some(value),
                    Mnemonic::TI => drive.temperature = Some(value),
                    Mnemonic::UM => drive.unit_mode = Some(value),
                    _ => {}
                }
                match (command, drive.stream.as_mut()) {
                    (Mnemonic::PT, Some(stream)) => {
                        stream.read_index(value).err().map(|e| match e {
                            FlowError::Underflow => DriveFault::Underflow { joint },
                            FlowError::Overrun => DriveFault::Overrun { joint },
                        })
                    }
                    (Mnemonic::BG, _) if value != 0 => {
                        Some(DriveFault::BeginRefused { joint, value })
                    }
                    _ => None,
                }
            }
        };
        if let Some(fault) = fault {
            self.raise(fault);
        }
    }

    fn on_emergency(&mut self, node: NodeId, emergency: DriveEmergency) {
        let Some((joint, _)) = self.drive_mut(node) else {
            self.ignored();
            return;
        };
        let count = |n: &mut u32| *n = n.saturating_add(1);
        // Only faults stop the arm. The seed stopped on every emergency but the Hall one,
        // including the queue-low warning it had armed itself (spec §9 item 35).
        let fault = match emergency {
            DriveEmergency::ErrorReset => return,
            DriveEmergency::DigitalHall => return count(&mut self.stats.hall_warnings),
            DriveEmergency::QueueLow { .. } => return count(&mut self.stats.queue_low_warnings),
            DriveEmergency::QueueFull { .. } => DriveFault::Overrun { joint },
            DriveEmergency::MotionTerminated {
                reason: REASON_UNDERFLOW,
                ..
            } => DriveFault::Underflow { joint },
            DriveEmergency::HeartbeatLost => DriveFault::HeartbeatLost { joint },
            DriveEmergency::MotionTerminated { .. }
            | DriveEmergency::MessageLost
            | DriveEmergency::WritePointerOutOfRange { .. }
            | DriveEmergency::PdoNotMapped { .. }
            | DriveEmergency::Other(_) => DriveFault::Emergency {
                joint,
                emcy: emergency.encode(),
            },
        };
        self.raise(fault);
    }

    fn on_sdo(&mut self, node: NodeId, response: SdoResponse) {
        let (cycle, group) = (self.cycle, self.timing.group);
        let Some((joint, drive)) = self.drive_mut(node) else {
            self.ignored();
            return;
        };
        drive.link.heard(cycle);
        let mapping = drive.step.configuration(drive.node, group);
        let fault = match mapping {
            // An answer to this drive's mapping transfer: checked.
            Some((step, read_back)) if response.object() == step.object => {
                let checked = if read_back {
                    step.check_read_back(&response)
                } else {
                    step.check_write(&response)
                };
                match checked {
                    Ok(()) => {
                        drive.awaiting.clear();
                        None
                    }
                    Err(refusal) => Some(DriveFault::MappingRefused {
                        joint,
                        object: step.object,
                        code: match refusal {
                            MappingRefusal::Abort(code) => Some(code),
                            MappingRefusal::Mismatch { .. } | MappingRefusal::Unexpected => None,
                        },
                    }),
                }
            }
            _ => {
                let object = response.object();
                let Some(at) = drive
                    .awaiting
                    .iter()
                    .position(|frame| frame.answered_by_sdo(object))
                else {
                    // Not awaited: the answer to a mapping transfer after a fallback.
                    return self.ignored();
                };
                drive.awaiting.swap_remove(at);
                if let SdoResponse::Abort { code, .. } = response {
                    return self.raise(DriveFault::SdoAbort { joint, code });
                }
                None
            }
        };
        if let Some(fault) = fault {
            self.refuse_mapping(fault);
        }
    }
}

/// Sends the frames of `drive`'s current start step; the step now waits for their answers.
fn send_step<B: CanBus>(drive: &mut Drive, ctx: &StepContext, out: &mut Outbox<'_, B>) {
    drive.awaiting.clear();
    // By reference: dropping heapless's by-value iterator has a panic path.
    for frame in &drive.step.frames(ctx) {
        out.request(drive, frame);
        let _ = drive.awaiting.push(*frame);
    }
    drive.step_sent = true;
    drive.retry.sent(out.cycle);
}

/// Sends all the frames of `drive`'s current start step again, in their order (see
/// [`super::retry`]; an `MP` write forgets the points written before it): the drive now owes
/// only their answers.
fn resend_step<B: CanBus>(drive: &mut Drive, ctx: &StepContext, out: &mut Outbox<'_, B>) {
    let frames = drive.step.frames(ctx);
    // A drive answers the interpreter only when operational: its NMT start may have been the
    // frame lost. Starting a started node changes nothing.
    if frames
        .iter()
        .any(|frame| matches!(frame, Outgoing::Interpreter(_)))
    {
        let start = Nmt {
            command: NmtCommand::Start,
            node: Some(drive.node),
        };
        out.send(&start.to_frame());
    }
    drive.awaiting.clear();
    for frame in &frames {
        out.request(drive, frame);
        let _ = drive.awaiting.push(*frame);
    }
    drive.link.resent(frames.len() as u32, out.cycle);
}

/// This cycle's sending: frames go to the bus, requests are counted on their drive's link,
/// and the first failure is kept.
struct Outbox<'a, B: CanBus> {
    bus: &'a mut B,
    cycle: u32,
    error: Option<TxError>,
}

impl<B: CanBus> Outbox<'_, B> {
    /// Sends `frame`; false if the bus refused it.
    fn send(&mut self, frame: &CanFrame) -> bool {
        match self.bus.try_transmit(frame) {
            Ok(()) => true,
            Err(error) => {
                self.error.get_or_insert(error);
                false
            }
        }
    }

    /// Sends a request to `drive`, which now owes an answer.
    fn request(&mut self, drive: &mut Drive, frame: &Outgoing) {
        let frame = match *frame {
            Outgoing::Interpreter(request) => request.to_frame(drive.node),
            Outgoing::Sdo(request) => request.to_frame(drive.node),
        };
        if self.send(&frame) {
            drive.link.sent(self.cycle);
        }
    }
}
