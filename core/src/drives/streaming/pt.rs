//! Writing PT points into a drive's ring and pacing them by its read index (spec §6.6).
//!
//! The drive model (SimplIQ software manual, "PT motion"): while the read index is `r`, the
//! drive moves from `QP[r]` to `QP[r+1]` in `MP[4]` samples, on a cubic whose end slope uses
//! `QP[r+2]`; so when segment `r` starts the drive fetches `QP[r+2]`. A point written while the
//! drive runs segment `r` can therefore go no nearer than slot `r + 3`, where it is fetched at
//! the next segment start and reached two segments later: between 2 and 3 control periods
//! after it was written. [`TARGET_LEAD`] keeps every point exactly there. (The seed kept five
//! points queued, ≈ 97 ms at 51 Hz, and backtracked on stop, §9 item 36.)
//!
//! Points are numbered by a sequence number `n` (1, 2, …) that lives in slot
//! `(n − 1) mod ring + 1`. The drive's read index, asked for every few cycles right after that
//! cycle's point, gives the lead `newest − r`:
//!
//! * 3: on target.
//! * 4: the drive fell one segment behind the controller (its clock is slower): the next point
//!   is skipped, so the drive plays one segment at double speed once.
//! * 2: the drive's segment boundary fell between the point and the query, or the drive's
//!   clock is faster and is about to overtake the controller: two points are written next
//!   cycle (a midpoint first), so the drive plays one set-point's motion over two segments.
//! * 1 or less (the drive has fetched a point not yet written) or 5 or more (it stopped
//!   taking points): the stream is lost and the manager stops.
//!
//! With equal clocks the lead stays at 3 after the start; clock drift costs one skip or one
//! insertion each time the drive's segment boundaries slide a full period relative to the
//! control cycle (e.g. every 100 s at 100 Hz for a 100 ppm difference).

use armgate_protocol::can::interpreter::Index;
use heapless::Vec;

/// Points between the newest written and the drive's read index, in steady state.
pub const TARGET_LEAD: u32 = 3;

/// Points written before the motion begins: `QP[1..=4]` all hold the start position, so the
/// first streamed point (the 5th) is due two segments after `BG`.
pub const FILLED_POINTS: u16 = 4;

/// Why the stream cannot go on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FlowError {
    /// The drive has reached points that were not written in time.
    Underflow,
    /// The drive is no longer consuming points, or reports an index outside the ring.
    Overrun,
}

/// What the next write does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Correction {
    /// One point.
    None,
    /// No point this cycle.
    Skip,
    /// Two points: a midpoint, then the target.
    Insert,
}

/// The writer side of one drive's PT ring.
#[derive(Clone, Debug, PartialEq)]
pub struct PtStream {
    ring: u16,
    /// Sequence number of the newest point written.
    newest: u32,
    /// Its value (counts).
    newest_value: i32,
    correction: Correction,
    /// `newest` when the read index was last asked for.
    asked_at: Option<u32>,
    /// The lead at the last answer.
    lead: Option<u32>,
}

impl PtStream {
    /// A ring of `ring` slots whose first [`FILLED_POINTS`] slots hold `position`.
    pub fn new(ring: u16, position: i32) -> Self {
        Self {
            ring: ring.max(1),
            newest: u32::from(FILLED_POINTS),
            newest_value: position,
            correction: Correction::None,
            asked_at: None,
            lead: None,
        }
    }

    /// The slot (1..=ring) of point `n`.
    fn slot(&self, n: u32) -> Index {
        let slot = n.saturating_sub(1) % u32::from(self.ring) + 1;
        // ring ≤ u16::MAX, so the slot fits.
        Index::new(slot as u16).unwrap_or_default()
    }

    /// This cycle's writes towards `target` (counts): (slot, value) pairs, none when a point is
    /// skipped, two when one is inserted.
    pub fn points(&mut self, target: i32) -> Vec<(Index, i32), 2> {
        let mut points = Vec::new();
        let mut push = |stream: &mut Self, value: i32| {
            stream.newest += 1;
            stream.newest_value = value;
            let _ = points.push((stream.slot(stream.newest), value));
        };
        match core::mem::replace(&mut self.correction, Correction::None) {
            Correction::Skip => {}
            Correction::None => push(self, target),
            Correction::Insert => {
                let mid = (i64::from(self.newest_value) + i64::from(target)) / 2;
                // The mean of two i32 values is an i32.
                push(self, mid as i32);
                push(self, target);
            }
        }
        points
    }

    /// Records that the read index is being asked for, right after this cycle's point.
    pub fn asked(&mut self) {
        self.asked_at = Some(self.newest);
    }

    /// Takes the drive's answer to the last read-index query (a slot number) and decides the
    /// next correction.
    pub fn read_index(&mut self, reported: i32) -> Result<(), FlowError> {
        let Some(asked_at) = self.asked_at.take() else {
            return Ok(()); // not asked for: an answer to someone else's query
        };
        let ring = i64::from(self.ring);
        if !(1..=ring).contains(&i64::from(reported)) {
            return Err(FlowError::Overrun);
        }
        // The sequence number ≡ `reported` nearest to where the drive should be.
        let expected = i64::from(asked_at) - i64::from(TARGET_LEAD);
        let expected_slot = (expected - 1).rem_euclid(ring) + 1;
        let offset = (i64::from(reported) - expected_slot + ring / 2).rem_euclid(ring) - ring / 2;
        let lead = i64::from(asked_at) - (expected + offset);
        self.lead = u32::try_from(lead).ok();
        self.correction = match lead {
            ..=1 => return Err(FlowError::Underflow),
            2 => Correction::Insert,
            3 => Correction::None,
            4 => Correction::Skip,
            _ => return Err(FlowError::Overrun),
        };
        Ok(())
    }

    /// The lead at the last read-index answer.
    pub fn lead(&self) -> Option<u32> {
        self.lead
    }
}
