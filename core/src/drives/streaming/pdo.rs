//! The PDO schedule's flow control: how many PT points a drive gets per cycle, paced by the
//! PT pointers its synchronous transmit PDO reports.
//!
//! Each cycle the manager sends one SYNC, then one receive PDO per drive carrying the next PT
//! point; the drive writes it at its own write pointer and advances the pointer. Every drive
//! answers each SYNC with a transmit PDO: its position and its PT head (write) and tail (read)
//! pointers, sampled at the SYNC. The manager reads it at the start of the next cycle.
//!
//! The lead at a SYNC is the number of points written beyond the read pointer, `head − 1 −
//! tail` modulo the ring. While the drive runs segment `r` it has fetched `QP[r+1]`, the
//! segment's end, and nothing beyond (Elmo's manual, docs/drives.md "PT flow control"), so a
//! lead of 1 is the least that has not run dry, and 0 means it has. Where the drive's segment
//! boundaries fall within the control cycle decides the least safe lead: 1 when a boundary
//! falls between the cycle's PT point and the next SYNC (the point is fetched at that very
//! boundary), 2 when it falls between the SYNC and the point (the point then comes too late
//! for that boundary). The phase drifts with the drive's clock, and SYNC samples cannot see
//! where it is, so the stream keeps [`PDO_TARGET_LEAD`](crate::config::PDO_TARGET_LEAD) = 2 at every SYNC: safe in both
//! phases, and a point lost on the bus or a clock slip costs one insertion, not an underflow.
//! Either way a point is fetched at the first segment start after it arrives and reached one
//! segment later: under two set-points from write to reached.
//!
//! The feedback is a cycle old when it arrives, and the points sent since are known, so the
//! stream predicts the lead at the SYNC it is about to send (one segment consumed per cycle)
//! and sends 0, 1 or 2 points to bring the next one to the target: a dead-beat correction
//! without waiting for the effect to show. A missing report is replaced by the prediction.
//!
//! The head pointer counts the points the drive received: a report whose head moved less than
//! the points sent before its SYNC shows points lost on the bus ([`PdoStream::take_lost`]), for
//! the adaptive lead ([`super::AdaptiveLead`]). A clock slip moves only the tail, and a lost
//! SYNC or transmit PDO only delays the report that counts the points, so neither reads as a
//! lost point.

use heapless::Vec;

use super::{FlowError, LeadChange};

/// The writer side of one drive's PT ring on the PDO schedule.
#[derive(Clone, Debug, PartialEq)]
pub struct PdoStream {
    /// Entries of the ring (at least 6).
    ring: u16,
    /// The lead kept at every SYNC (1 or more).
    target: u16,
    /// The least lead kept: the target, one less for a drive whose boundary precedes the SYNC
    /// (known from its first report).
    least: Option<i32>,
    /// The value of the newest point sent (counts), for a midpoint.
    newest_value: i32,
    /// The lead at the last SYNC sent: reported, or predicted.
    lead_at_sync: i32,
    /// Points sent after the last SYNC.
    sent_since_sync: u8,
    /// The lead of the last report.
    reported: Option<u16>,
    /// SYNCs sent since the last report.
    unreported: u32,
    /// Points the lead has been raised (or lowered, below 0) since the start.
    raised: i32,

    /// The head pointer of the last report.
    head: Option<u16>,
    /// Points sent between the last reported SYNC and the last SYNC sent.
    sent_unreported: u16,
    /// Points lost on the bus, seen in reports since the last [`Self::take_lost`].
    lost: u16,
}

impl PdoStream {
    /// A ring of `ring` entries (≥ 6) keeping `target` points beyond the read pointer at every
    /// SYNC, begun with `filled` points holding `position`.
    pub fn new(ring: u16, target: u16, filled: u16, position: i32) -> Self {
        Self {
            ring: ring.max(6),
            target: target.max(1),
            least: None,
            newest_value: position,
            // At the first SYNC the drive runs segment 1 with points 1..=filled: `filled − 1`
            // beyond it, which is what the first prediction (one segment less) gives.
            lead_at_sync: i32::from(filled),
            sent_since_sync: 0,
            reported: None,
            unreported: 0,
            raised: 0,
            head: None,
            sent_unreported: 0,
            lost: 0,
        }
    }

    /// The lead that the pointers `head` (the next entry to write) and `tail` (the read
    /// pointer) give, both `1..=ring`.
    pub fn lead_of(&self, head: u16, tail: u16) -> Option<u16> {
        let valid = |p: u16| (1..=self.ring).contains(&p);
        (valid(head) && valid(tail)).then(|| (head + 2 * self.ring - 1 - tail) % self.ring)
    }

    /// Takes the pointers of the transmit PDO answering the last SYNC.
    pub fn feedback(&mut self, head: u16, tail: u16) -> Result<(), FlowError> {
        let lead = self.lead_of(head, tail).ok_or(FlowError::Overrun)?;
        self.reported = Some(lead);
        self.unreported = 0;
        // Every drive began with the same points at the same instant, so the first report
        // differs from the prediction only by where the drive's segment boundary falls: before
        // the SYNC it reads one less, and that is where it stays.
        let phase = (i32::from(lead) - self.lead_at_sync).clamp(-1, 0);
        self.least
            .get_or_insert((i32::from(self.target) + phase).max(1));
        // The report is the last SYNC's: it replaces the prediction; the points sent after
        // that SYNC are still counted in `sent_since_sync`.
        self.lead_at_sync = i32::from(lead);
        self.count_lost(head);
        match lead {
            ..=0 => Err(FlowError::Underflow),
            l if l + 1 >= self.ring => Err(FlowError::Overrun),
            _ => Ok(()),
        }
    }

    /// Points lost between the previous report and this one: the head should have moved by the
    /// points sent between their SYNCs (a head ahead of that is not a loss).
    fn count_lost(&mut self, head: u16) {
        if let Some(previous) = self.head {
            let ring = u32::from(self.ring);
            let expected = (u32::from(previous) + u32::from(self.sent_unreported)) % ring;
            let short = (expected + ring - u32::from(head) % ring) % ring;
            if short <= ring / 2 {
                // At most half the ring: fits a u16.
                self.lost = self.lost.saturating_add(short as u16);
            }
        }
        self.head = Some(head);
        self.sent_unreported = 0;
    }

    /// Points lost on the bus that the reports since the last call showed.
    pub fn take_lost(&mut self) -> u16 {
        core::mem::take(&mut self.lost)
    }

    /// A SYNC is going out: the drive consumes about one segment per cycle, and this cycle's
    /// points follow. Returns them (0, 1 or 2 values, a midpoint first) towards `target`.
    pub fn points(&mut self, target: i32) -> Vec<i32, 3> {
        self.points_with(target, LeadChange::Hold)
    }

    /// The same, with the lead changed by `change` from this cycle on: one point more (0 to 3
    /// values, evenly between the newest point and `target`) or one less than it would send.
    pub fn points_with(&mut self, target: i32, change: LeadChange) -> Vec<i32, 3> {
        // The predicted lead at this SYNC: the last one's, plus what was sent after it, minus
        // the segment consumed in between.
        let predicted = self.lead_at_sync + i32::from(self.sent_since_sync) - 1;
        self.lead_at_sync = predicted;
        self.unreported = self.unreported.saturating_add(1);
        self.sent_unreported = self
            .sent_unreported
            .saturating_add(self.sent_since_sync.into());
        // The lead at the next SYNC is this one plus this cycle's points minus the next
        // segment. Kept within least..=least + 1: as the drive's clock drifts, its boundary
        // passes the SYNC and its reading moves by one without a point more or less queued.
        let least = self.least.unwrap_or(i32::from(self.target)) + self.raised;
        let kept: i8 = match predicted {
            p if p > least + 1 => 0,
            p if p >= least => 1,
            _ => 2,
        };
        // A change moves every drive's lead by one, wherever it is in its band.
        let count = (kept + change.step()).max(0) as u8;
        self.raised += i32::from(change.step());
        let mut points = Vec::new();
        let (from, to, n) = (
            i64::from(self.newest_value),
            i64::from(target),
            i64::from(count),
        );
        for k in 1..=n {
            // A weighted mean of two i32 values is an i32.
            let _ = points.push(((from * (n - k) + to * k) / n) as i32);
        }
        self.sent_since_sync = count;
        if let Some(&last) = points.last() {
            self.newest_value = last;
        }
        points
    }

    /// Points the lead has been raised since the start (below 0: lowered).
    pub fn raised(&self) -> i32 {
        self.raised
    }

    /// The lead at the last report.
    pub fn lead(&self) -> Option<u32> {
        self.reported.map(u32::from)
    }

    /// SYNCs sent since the last report.
    pub fn unreported(&self) -> u32 {
        self.unreported
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::PDO_TARGET_LEAD;

    /// A drive that consumes one segment per cycle and answers every SYNC: the stream settles
    /// on the target lead and stays there.
    #[test]
    fn steady_state_keeps_the_target_lead() {
        let mut stream = PdoStream::new(6, PDO_TARGET_LEAD, 3, 0);
        let (mut head, mut tail) = (4u16, 1u16);
        let advance = |p: u16, n: u16| (p - 1 + n) % 6 + 1;
        for cycle in 0..50 {
            // The SYNC samples the pointers, the points land, the answer is read, a segment
            // passes.
            let at_sync = (head, tail);
            head = advance(head, stream.points(cycle).len() as u16);
            if cycle > 0 {
                assert_eq!(stream.lead_of(at_sync.0, at_sync.1), Some(PDO_TARGET_LEAD));
            }
            stream.feedback(at_sync.0, at_sync.1).unwrap();
            tail = advance(tail, 1);
        }
    }

    #[test]
    fn a_lost_point_is_made_up_and_an_extra_one_skipped() {
        let mut stream = PdoStream::new(6, PDO_TARGET_LEAD, 3, 0);
        // Lead 1 at the last SYNC (the drive's boundary precedes the SYNC: it keeps 1) and
        // nothing sent since: 0 at this one, two points needed, a midpoint first.
        stream.feedback(5, 3).unwrap();
        assert_eq!(stream.points(10).as_slice(), &[5, 10]);
        // Lead 3 reported, two points sent after it: 4 at this SYNC, skip.
        stream.feedback(2, 4).unwrap();
        assert!(stream.points(20).is_empty());
        // Lead 3 reported, nothing sent after it: 2 at this SYNC, one point.
        stream.feedback(2, 4).unwrap();
        assert_eq!(stream.points(30).as_slice(), &[30]);
    }

    #[test]
    fn a_raise_adds_a_point_between_and_a_lower_skips_one() {
        let mut stream = PdoStream::new(16, PDO_TARGET_LEAD, 3, 0);
        // Lead 2 at the last SYNC, one point sent after it: 2 at this one, one point kept.
        stream.feedback(5, 2).unwrap();
        assert_eq!(stream.points(10).as_slice(), &[10]);
        // Raised: one more, between the newest point and the target.
        assert_eq!(
            stream.points_with(40, LeadChange::Raise).as_slice(),
            &[25, 40]
        );
        // The band is one higher from now on: 3 kept.
        assert_eq!(stream.points(50).as_slice(), &[50]);
        assert_eq!(stream.raised(), 1);
        // A point short and a raise on top: three, evenly spaced.
        stream.feedback(7, 5).unwrap(); // lead 1
        assert_eq!(
            stream.points_with(80, LeadChange::Raise).as_slice(),
            &[60, 70, 80]
        );
        // Lowered: one less than kept.
        assert!(stream.points_with(90, LeadChange::Lower).is_empty());
        assert_eq!(stream.raised(), 1);
    }

    #[test]
    fn the_head_counts_points_lost_but_not_a_missing_report_or_a_slip() {
        let mut stream = PdoStream::new(16, PDO_TARGET_LEAD, 3, 0);
        stream.feedback(4, 1).unwrap();
        let _ = stream.points(1); // one point after SYNC 1
        let _ = stream.points(2); // SYNC 2, one point after it
        // The report of SYNC 2: the first point arrived.
        stream.feedback(5, 2).unwrap();
        assert_eq!(stream.take_lost(), 0);
        // SYNC 3's report is missing (a lost SYNC or TPDO3); SYNC 4's counts both points.
        let _ = stream.points(3);
        let _ = stream.points(4);
        stream.feedback(7, 4).unwrap();
        assert_eq!(stream.take_lost(), 0);
        // A slip moves the tail only.
        let _ = stream.points(5);
        stream.feedback(8, 6).unwrap();
        assert_eq!(stream.take_lost(), 0);
        // The head did not move for the point sent: lost, counted once.
        let _ = stream.points(6);
        stream.feedback(8, 6).unwrap();
        assert_eq!(stream.take_lost(), 1);
        assert_eq!(stream.take_lost(), 0);
    }

    #[test]
    fn pointers_outside_the_ring_or_the_window_stop_the_stream() {
        let mut stream = PdoStream::new(6, PDO_TARGET_LEAD, 3, 0);
        assert_eq!(stream.feedback(0, 1), Err(FlowError::Overrun));
        assert_eq!(stream.feedback(7, 1), Err(FlowError::Overrun));
        assert_eq!(stream.feedback(2, 1), Err(FlowError::Underflow)); // lead 0
        assert_eq!(stream.feedback(6, 6), Err(FlowError::Overrun)); // lead 5
        assert_eq!(stream.feedback(3, 1), Ok(())); // lead 1
        assert_eq!(stream.feedback(4, 1), Ok(())); // lead 2
        assert_eq!(stream.lead(), Some(2));
    }
}
