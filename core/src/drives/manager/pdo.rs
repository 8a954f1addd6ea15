//! The drive manager's PDO schedule: the start's group id and its barriers, a refused
//! configuration and the fallback, the cycle's SYNC and receive PDOs, the transmit PDOs'
//! feedback, and the checks that stop the arm (a missing transmit PDO, a late SYNC).

use armgate_protocol::can::{
    Nmt, NmtCommand, NodeId, NodeMessage, PtFeedback, PtPoint, SyncObject, TimeStamp,
};
use heapless::Vec;

use super::{DriveManager, Outbox};
use crate::MAX_JOINTS;
use crate::config::Streaming;
use crate::drives::bus::CanBus;
use crate::drives::drive::{Drive, Joint};
use crate::drives::fault::DriveFault;
use crate::drives::startup::{Outgoing, StartStep};
use crate::drives::state::Phase;
use crate::drives::streaming::{FlowError, LeadChange, Query, Stream};

impl DriveManager {
    /// A stop just begun, with as many hold cycles as the schedule needs: as on the
    /// interpreter schedule two beyond the lead (the drive comes to rest past the second hold
    /// point), and one more because the PDO schedule has one point more queued right after a
    /// write than its lead at the SYNC.
    pub(super) fn with_hold_cycles(&self, phase: Phase) -> Phase {
        match (phase, self.streaming) {
            (Phase::Stopping(_), Streaming::Pdo) => {
                Phase::Stopping(u32::from(self.pdo_lead_now()) + 3)
            }
            _ => phase,
        }
    }

    /// PDO schedule, before a cycle's frames: the SYNC on time, and every drive's feedback.
    pub(super) fn check_pdo(&mut self, now: f64) {
        if matches!(self.phase, Phase::Streaming(_) | Phase::Stopping(_)) {
            self.check_sync(now);
        }
        if matches!(self.phase, Phase::Streaming(_)) {
            self.check_feedback();
        }
    }

    /// PDO schedule: a SYNC more than half a period late (the control cycle skipped ticks)
    /// is a fault: the drives' queues ran on without points. It is the cause of what the
    /// drives reported meanwhile (their underflows), so it replaces a fault raised by this
    /// cycle's receive.
    fn check_sync(&mut self, now: f64) {
        let period = self.timing.period;
        let Some(last) = self.last_sync else { return };
        let late = now - last - period;
        if late > 0.5 * period {
            // A float-to-integer `as` saturates: it cannot fail.
            let late_us = libm::round(late * 1e6) as u32;
            if self.faulted_in_receive {
                self.fault = None;
            }
            self.raise(DriveFault::LateSync { late_us });
        }
    }

    /// PDO schedule: faults the first drive whose transmit PDO has been missing for more than
    /// `DriveSettings::pdo_missing_cycles` SYNCs in a row.
    fn check_feedback(&mut self) {
        let missing = self.pdo_missing_cycles;
        let silent = self
            .joints
            .iter()
            .enumerate()
            .find_map(|(joint, entry)| match entry {
                Joint::Real(Drive {
                    stream: Some(Stream::Pdo(stream)),
                    ..
                }) if stream.unreported() > missing => Some(DriveFault::NoFeedback {
                    joint,
                    cycles: stream.unreported(),
                }),
                _ => None,
            });
        if let Some(fault) = silent {
            self.raise(fault);
        }
    }

    /// A drive refused the PDO mapping: a start-up fault, or with `drives.pdo_fallback` the
    /// interpreter schedule for this start (every drive still mapping goes on with its unit
    /// mode).
    pub(super) fn refuse_mapping(&mut self, fault: DriveFault) {
        if !self.may_fall_back {
            return self.raise(fault);
        }
        self.streaming = Streaming::Interpreter;
        self.fallback.get_or_insert(fault);
        self.for_each_drive(|drive| {
            // The reset communication goes out only once every drive has its group id, so a
            // refused group id leaves the drives as the NMT start left them.
            let next = match drive.step {
                StartStep::GroupId | StartStep::CheckGroupId | StartStep::Regroup => {
                    StartStep::ConsumerHeartbeat
                }
                StartStep::Map(_) => StartStep::ReadUnitMode,
                _ => return,
            };
            drive.step = next;
            drive.step_sent = false;
            drive.awaiting.clear();
        });
    }

    /// PDO schedule, the group id's barriers: when every drive has written it, the reset
    /// communication that makes it effective goes to all nodes; when every drive has waited
    /// the settle time after it, the NMT start, and the drives go on with their heartbeat.
    pub(super) fn regroup<B: CanBus>(&mut self, out: &mut Outbox<'_, B>) {
        let all_at = |joints: &Vec<Joint, MAX_JOINTS>, step: StartStep| {
            joints.iter().all(|joint| match joint {
                Joint::Real(drive) => drive.step == step && drive.step_sent,
                Joint::Pretend { .. } => true,
            })
        };
        let (command, next) = if all_at(&self.joints, StartStep::Regroup) {
            let settle = self.timing.nmt_settle;
            (NmtCommand::ResetCommunication, StartStep::Rejoin(settle))
        } else if all_at(&self.joints, StartStep::Rejoin(0)) {
            (NmtCommand::Start, StartStep::ConsumerHeartbeat)
        } else {
            return;
        };
        out.send(
            &Nmt {
                command,
                node: None,
            }
            .to_frame(),
        );
        self.for_each_drive(|drive| {
            drive.step = next;
            drive.step_sent = false;
        });
    }

    /// One PDO streaming cycle: the SYNC, then every running drive's point(s) towards its
    /// target in receive PDOs, then now and then a drive's temperature query and a Time
    /// Stamp; drives not yet running (a stop during the start) get a position query instead.
    /// The controller sends in queue order, so every drive's point lands at the same offset
    /// after the SYNC in every cycle (one more or one less only while a point is inserted or
    /// skipped): with drive clocks locked to the controller's, where a drive's segment
    /// boundary falls against its point never changes.
    pub(super) fn stream_pdo<B: CanBus>(
        &mut self,
        now: f64,
        streamed: u32,
        out: &mut Outbox<'_, B>,
    ) {
        out.send(&SyncObject.to_frame());
        let change = self.lead_change();
        let stats = &mut self.stats;
        for joint in self.joints.iter_mut() {
            let Joint::Real(drive) = joint else { continue };
            let stream = drive.stream.as_mut().and_then(Stream::pdo);
            if let (Some(target), Some(stream)) = (drive.target, stream) {
                let points = stream.points_with(target, change);
                for &position in &points {
                    out.send(&PtPoint { position }.to_frame(drive.node));
                }
                let add = |n: &mut u32, k: usize| {
                    *n = n.saturating_add(u32::try_from(k).unwrap_or(u32::MAX));
                };
                match points.len() {
                    0 => add(&mut stats.points_skipped, 1),
                    n => add(&mut stats.points_inserted, n - 1),
                }
            }
        }
        let schedule = self.schedule;
        for (index, joint) in self.joints.iter_mut().enumerate() {
            let Joint::Real(drive) = joint else { continue };
            let running = drive.target.is_some() && drive.stream.is_some();
            let query = match schedule.query(streamed, index, false) {
                Query::Position if running => continue,
                query => query,
            };
            out.request(drive, &Outgoing::Interpreter(query.request()));
        }
        // After the SYNC it refers to, and after the points, which it would otherwise delay
        // every `time_stamp_every` cycles.
        let every = u32::from(self.timing.time_stamp_every);
        if every != 0 && streamed.is_multiple_of(every) {
            out.send(
                &TimeStamp {
                    micros: micros(now),
                }
                .to_frame(),
            );
        }
    }

    /// PDO schedule: what the adaptive lead does this cycle, from the points the reports read
    /// in it showed lost and the reports missing. Only while streaming: a stop's hold points
    /// keep the lead.
    fn lead_change(&mut self) -> LeadChange {
        // A report missing (a SYNC or a TPDO3 lost) is not a point lost, but it shows the bus
        // losing frames: raising on it too often comes before the first point lost.
        let mut missing = false;
        self.for_each_drive(|drive| {
            if let Some(Stream::Pdo(stream)) = &drive.stream {
                missing |= stream.unreported() > 0;
            }
        });
        if missing {
            self.lead_policy.saw_loss();
        }
        if !matches!(self.phase, Phase::Streaming(_)) {
            return LeadChange::Hold;
        }
        let change = self.lead_policy.cycle();
        let count = |n: &mut u32| *n = n.saturating_add(1);
        match change {
            LeadChange::Raise => count(&mut self.stats.lead_raised),
            LeadChange::Lower => count(&mut self.stats.lead_lowered),
            LeadChange::Hold => {}
        }
        change
    }

    /// A drive's transmit PDO: its position and PT pointers at the last SYNC.
    pub(super) fn on_feedback(&mut self, node: NodeId, feedback: PtFeedback) {
        let cycle = self.cycle;
        let Some((joint, drive)) = self.drive_mut(node) else {
            self.ignored();
            return;
        };
        drive.position = Some(feedback.position);
        // The drive is alive: a lost answer to a temperature query is not a silent drive.
        drive.link.heard(cycle);
        let mut lost = 0;
        let flow = drive.stream.as_mut().and_then(Stream::pdo).map(|stream| {
            let flow = stream.feedback(feedback.head, feedback.tail);
            lost = stream.take_lost();
            flow
        });
        if lost > 0 {
            // Seen even when this report faults the drive: the restart begins higher.
            self.lead_policy.saw_loss();
            self.stats.points_lost = self.stats.points_lost.saturating_add(lost.into());
        }
        match flow {
            Some(Err(FlowError::Underflow)) => self.raise(DriveFault::Underflow { joint }),
            Some(Err(FlowError::Overrun)) => self.raise(DriveFault::Overrun { joint }),
            _ => {}
        }
    }
}

/// The controller's clock for a Time Stamp: `now` (s), the tick's scheduled time, in
/// microseconds, wrapping at 2³² as the drives' motion clocks do. The SYNC leaves after the
/// tick's receive half and the controller's step, and after any frame already on the wire:
/// a constant part the first pair takes out, and jitter the drives' filter smooths.
fn micros(now: f64) -> u32 {
    // Saturating in the float-to-integer cast (0 for NaN), then wrapping by truncation.
    (libm::round(now * 1e6) as u64) as u32
}
