//! The drive manager's start sequence: every drive's steps, sent, answered or repeated, and
//! the `BG` that begins streaming on the schedule of the start.

use armgate_protocol::can::interpreter::{Index, Mnemonic, Request};
use armgate_protocol::can::{Nmt, NmtCommand, NodeMessage};

use super::{DriveManager, Outbox};
use crate::config::Streaming;
use crate::drives::bus::CanBus;
use crate::drives::drive::{Drive, Joint};
use crate::drives::fault::DriveFault;
use crate::drives::settings::Timing;
use crate::drives::startup::{Outgoing, StartStep, StepContext};
use crate::drives::state::Phase;
use crate::drives::streaming::{FILLED_POINTS, PdoStream, PtStream, Stream};

impl DriveManager {
    /// One cycle of the start sequence: each drive advances when its step is answered and
    /// sends the next step's frames; when every drive is ready, all get `BG` in one cycle.
    pub(super) fn start_steps<B: CanBus>(&mut self, out: &mut Outbox<'_, B>) {
        let (timing, ring, streaming) = (self.timing, self.ring(), self.streaming);
        let mut fault = None;
        for (index, joint) in self.joints.iter_mut().enumerate() {
            let Joint::Real(drive) = joint else { continue };
            let answered = drive.step_sent && drive.awaiting.is_empty();
            let position_known = drive.step != StartStep::ReadPosition || drive.position.is_some();
            if answered && position_known {
                let settle = timing.unit_mode_settle;
                match drive
                    .step
                    .next(drive.unit_mode, settle, streaming, ring.filled)
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
                send_step(drive, &ring.context(&timing, drive), out);
            } else if !drive.awaiting.is_empty() && drive.retry.due(out.cycle, timing.reply_timeout)
            {
                resend_step(drive, &ring.context(&timing, drive), out);
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
            self.begin(ring, out);
        }
    }

    /// The PT ring of this start: the interpreter's, or the PDO schedule's filled with one
    /// point more than the lead, and at least `FILLED_POINTS` (the first point streamed after
    /// `BG` is then due at the second segment start, not the first).
    fn ring(&self) -> Ring {
        match self.streaming {
            Streaming::Interpreter => Ring {
                len: self.ring_len,
                filled: FILLED_POINTS,
            },
            Streaming::Pdo => Ring {
                len: self.pdo_ring_len,
                filled: self.pdo_lead_now().saturating_add(1).max(FILLED_POINTS),
            },
        }
    }

    /// Every drive is ready: `BG` (on the PDO schedule one to the group, so that every drive
    /// begins at once) and each drive's stream.
    fn begin<B: CanBus>(&mut self, ring: Ring, out: &mut Outbox<'_, B>) {
        let (timing, streaming) = (self.timing, self.streaming);
        if streaming == Streaming::Pdo {
            let begin = Request::Query {
                command: Mnemonic::BG,
                index: Index::ZERO,
            };
            out.send(&begin.to_frame(timing.group));
        }
        // A request repeated in this start (its answer lost) is the bus losing frames before
        // any point is streamed: the streams begin `START_RAISE` points higher, instead of
        // learning it from the first lost point, which at the least lead underflows its drive
        // before any report can show it. The ring was filled for the lower lead; the streams
        // make up the points in their first cycles.
        self.lead_policy.restart();
        let pdo_lead = self.pdo_lead_now();
        self.for_each_drive(|drive| {
            let Some(position) = drive.target else { return };
            drive.step = StartStep::Begin;
            let ctx = ring.context(&timing, drive);
            match streaming {
                Streaming::Interpreter => {
                    drive.stream = Some(Stream::Interpreter(PtStream::new(ring.len, position)));
                    send_step(drive, &ctx, out);
                }
                Streaming::Pdo => {
                    let stream = PdoStream::new(ring.len, pdo_lead, ring.filled, position);
                    drive.stream = Some(Stream::Pdo(stream));
                    // The group `BG` went out: each drive owes its answer.
                    drive.awaiting.clear();
                    for frame in &drive.step.frames(&ctx) {
                        let _ = drive.awaiting.push(*frame);
                        drive.link.sent(out.cycle);
                    }
                    drive.step_sent = true;
                }
            }
        });
        self.phase = Phase::Streaming(0);
    }
}

/// The PT ring a start configures: its entries, and the points it is filled with before `BG`.
#[derive(Clone, Copy)]
struct Ring {
    len: u16,
    filled: u16,
}

impl Ring {
    /// What `drive`'s start steps need to know.
    fn context(self, timing: &Timing, drive: &Drive) -> StepContext {
        StepContext {
            controller: timing.controller,
            heartbeat_timeout_ms: timing.heartbeat_timeout_ms,
            ring_len: self.len,
            samples_per_point: timing.samples_per_point,
            position: drive.target,
            filled: self.filled,
            node: drive.node,
            group: timing.group,
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
