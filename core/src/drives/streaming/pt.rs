//! Writing PT points into a drive's ring and pacing them by its read index (spec §6.6).
//!
//! The drive model (Elmo HARmonica software manual §12.1.7.4, docs/drives.md "PT flow
//! control"): while the read index is `r`, the drive moves from `QP[r]` to `QP[r+1]` in `MP[4]`
//! samples; when segment `r` starts it fetches `QP[r+1]`, its own end, and nothing beyond. A
//! point written while the drive runs segment `r` can therefore go no nearer than slot `r + 2`,
//! where it is fetched at the next segment start and reached one segment later: between 1 and
//! 2 control periods after it was written. [`TARGET_LEAD`] keeps every point exactly there.
//! (The seed kept five points queued, ≈ 97 ms at 51 Hz, and backtracked on stop, §9 item 36.)
//!
//! Point `n` (1, 2, …) lives in slot `(n − 1) mod ring + 1`; only the slot of the newest point
//! is kept, so nothing wraps however long the stream runs. The drive's read index, asked for
//! every few cycles right after that cycle's point, gives the lead `newest − r` (mod ring):
//!
//! * 2: on target.
//! * 3: the drive fell one segment behind the controller (its clock is slower): the next point
//!   is skipped, so the drive plays one segment at double speed once.
//! * 1: the drive's segment boundary fell between the point and the query, or the drive's
//!   clock is faster and is about to overtake the controller: two points are written next
//!   cycle (a midpoint first), so the drive plays one set-point's motion over two segments.
//! * 0 or less (the drive has fetched a point not yet written) or 4 or more (it stopped
//!   taking points): the stream is lost and the manager stops.
//!
//! With equal clocks the lead stays at 2 after the start; clock drift costs one skip or one
//! insertion each time the drive's segment boundaries slide a full period relative to the
//! control cycle (e.g. every 100 s at 100 Hz for a 100 ppm difference).

use core::num::NonZeroU32;

use armgate_protocol::can::interpreter::Index;
use heapless::Vec;

/// Points between the newest written and the drive's read index, in steady state.
pub const TARGET_LEAD: u32 = 2;

/// Points written before the motion begins: `QP[1..=3]` all hold the start position, so the
/// first streamed point (the 4th) is due when the second segment after `BG` starts.
pub const FILLED_POINTS: u16 = 3;

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
///
/// Points are tracked by their slot, not by an ever-growing sequence number: a `u32` counter
/// wraps after 2³² points (≈ 251 days at 198 Hz), and since 2³² is no multiple of the ring
/// length the point after the wrap would land in the wrong slot, skipping one. Every quantity
/// below is a slot or a difference of slots modulo the ring, so there is nothing to wrap.
#[derive(Clone, Debug, PartialEq)]
pub struct PtStream {
    ring: NonZeroU32,
    /// Slot (0-based, `< ring`) of the newest point written.
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
    /// A ring of `ring` slots (at least one) whose first [`FILLED_POINTS`] slots hold
    /// `position`.
    pub fn new(ring: u16, position: i32) -> Self {
        let ring = NonZeroU32::new(u32::from(ring)).unwrap_or(NonZeroU32::MIN);
        Self {
            ring,
            newest: (u32::from(FILLED_POINTS) + ring.get() - 1) % ring,
            newest_value: position,
            correction: Correction::None,
            asked_at: None,
            lead: None,
        }
    }

    /// The ring slot (1..=ring, the drive's `QP` index) of the newest point.
    fn newest_index(&self) -> Index {
        // newest < ring ≤ u16::MAX, so newest + 1 fits.
        Index::new(u16::try_from(self.newest + 1).unwrap_or(u16::MAX)).unwrap_or_default()
    }

    /// This cycle's writes towards `target` (counts): (slot, value) pairs, none when a point is
    /// skipped, two when one is inserted.
    pub fn points(&mut self, target: i32) -> Vec<(Index, i32), 2> {
        let mut points = Vec::new();
        let mut push = |stream: &mut Self, value: i32| {
            // newest < ring, so newest + 1 ≤ u16::MAX cannot overflow.
            stream.newest = (stream.newest + 1) % stream.ring;
            stream.newest_value = value;
            let _ = points.push((stream.newest_index(), value));
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
        let ring = self.ring;
        let reported = match u32::try_from(reported) {
            Ok(slot @ 1..) if slot <= ring.get() => slot - 1,
            _ => return Err(FlowError::Overrun),
        };
        // Where the drive should be: TARGET_LEAD slots behind the newest point when asked.
        let lead_slots = TARGET_LEAD % ring;
        let expected = (asked_at + ring.get() - lead_slots) % ring;
        // How far the drive is ahead of that, taken in -ring/2 .. ring/2. All terms are below
        // the ring length (≤ u16::MAX), so the sums cannot overflow.
        let half = ring.get() / 2;
        let shifted = (reported + ring.get() - expected + half) % ring;
        let ahead = i64::from(shifted) - i64::from(half);
        let lead = i64::from(TARGET_LEAD) - ahead;
        self.lead = u32::try_from(lead).ok();
        self.correction = match lead {
            ..=0 => return Err(FlowError::Underflow),
            1 => Correction::Insert,
            2 => Correction::None,
            3 => Correction::Skip,
            _ => return Err(FlowError::Overrun),
        };
        Ok(())
    }

    /// The lead at the last read-index answer.
    pub fn lead(&self) -> Option<u32> {
        self.lead
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The slots of the points written from now on, `count` cycles, answering each read-index
    /// query as a drive exactly `lead` points behind would.
    fn slots(stream: &mut PtStream, count: usize, lead: u32, ring: u32) -> std::vec::Vec<u16> {
        let mut out = std::vec::Vec::new();
        for _ in 0..count {
            out.extend(stream.points(7).iter().map(|(slot, _)| slot.get()));
            stream.asked();
            let newest = stream.newest;
            let reported = (newest + ring * 4 - lead) % ring + 1;
            stream.read_index(reported as i32).unwrap();
        }
        out
    }

    #[test]
    fn slots_run_round_the_ring_without_a_gap() {
        // Far more points than the ring holds, so it wraps many times; every point goes to the
        // slot after the previous one, 1 after 6.
        let mut stream = PtStream::new(6, 0);
        let written = slots(&mut stream, 40, TARGET_LEAD, 6);
        assert_eq!(written.first(), Some(&4)); // QP[1..=3] were filled
        for pair in written.windows(2) {
            if let [a, b] = pair {
                assert_eq!(*b, *a % 6 + 1, "{written:?}");
            }
        }
        assert_eq!(stream.lead(), Some(TARGET_LEAD));
    }

    #[test]
    fn corrections_across_the_ring_end_keep_the_slots_consistent() {
        // A drive one behind (lead 3) makes the next point skip; one ahead (lead 1) makes two
        // points, a midpoint first. Both exercised right at the ring's end (slot 6 → 1).
        let mut stream = PtStream::new(6, 0);
        assert_eq!(slots(&mut stream, 3, TARGET_LEAD, 6), [4, 5, 6]);
        stream.asked();
        stream.read_index(3).unwrap(); // newest 6, drive at 3: lead 3
        assert_eq!(stream.lead(), Some(3));
        assert!(stream.points(9).is_empty());
        stream.asked();
        stream.read_index(5).unwrap(); // newest 6, drive at 5: lead 1
        assert_eq!(stream.lead(), Some(1));
        let two: std::vec::Vec<_> = stream
            .points(10)
            .iter()
            .map(|(s, v)| (s.get(), *v))
            .collect();
        assert_eq!(two, [(1, 8), (2, 10)]);
        assert_eq!(slots(&mut stream, 5, TARGET_LEAD, 6), [3, 4, 5, 6, 1]);
    }

    #[test]
    fn answers_outside_the_ring_or_the_lead_window_stop_the_stream() {
        let mut stream = PtStream::new(6, 0);
        let _ = stream.points(0); // newest: slot 4
        for (reported, error) in [
            (0, FlowError::Overrun),
            (7, FlowError::Overrun),
            (-1, FlowError::Overrun),
            (4, FlowError::Underflow), // lead 0
            (5, FlowError::Overrun),   // lead −1 ≡ 5: taken as 5
            (6, FlowError::Overrun),   // lead 4
        ] {
            stream.asked();
            assert_eq!(stream.read_index(reported), Err(error), "{reported}");
        }
        stream.asked();
        assert_eq!(stream.read_index(2), Ok(()));
        assert_eq!(stream.lead(), Some(2));
    }
}
