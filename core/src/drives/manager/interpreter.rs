//! The drive manager's interpreter schedule: per drive and cycle its PT point(s) and one
//! query, paced by the read index the drive reports (spec §6.5).

use armgate_protocol::can::interpreter::{Mnemonic, Request, Value};
use heapless::Vec;

use super::{DriveManager, Outbox};
use crate::drives::bus::CanBus;
use crate::drives::drive::Joint;
use crate::drives::startup::Outgoing;
use crate::drives::streaming::{Query, Stream};

impl DriveManager {
    /// One streaming cycle (`streamed`: the cycle count the schedule staggers by): every
    /// running drive gets its point(s) towards its target and one query; drives not yet
    /// running (a stop during the start) only the query.
    pub(super) fn stream_interpreter<B: CanBus>(&mut self, streamed: u32, out: &mut Outbox<'_, B>) {
        let schedule = self.schedule;
        let stats = &mut self.stats;
        for (index, joint) in self.joints.iter_mut().enumerate() {
            let Joint::Real(drive) = joint else { continue };
            let points = match (
                drive.target,
                drive.stream.as_mut().and_then(Stream::interpreter),
            ) {
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
            if let (Query::ReadIndex, Some(stream)) =
                (query, drive.stream.as_mut().and_then(Stream::interpreter))
            {
                stream.asked();
            }
        }
    }
}
