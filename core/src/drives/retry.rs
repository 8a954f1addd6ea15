//! Start-up requests sent again when their answer does not come: a frame lost on the bus
//! (or its answer lost) costs a reply timeout, not the start.
//!
//! A step is sent again whole, its frames in their order (an `MP` write forgets the points
//! written before it), preceded by an NMT start to the drive if it has interpreter frames (a
//! drive that missed its NMT start answers no interpreter request). Only the start steps
//! before `BG` are repeated, and all of them are idempotent: SDO writes
//! and reads, interpreter writes (`MO`, `UM`, `MP`, `QP`, `PT`) and queries (`UM`, `PX`) leave
//! the drive as one copy does. Not repeated: `BG` (a second one restarts PT motion at the ring's
//! start), and the NMT broadcasts (reset communication, start), which have no answer to miss.

/// Times a start step's unanswered frames are sent again before the drive is declared silent
/// (ER30). At 1 % frame loss an attempt of a two-frame step fails 4 % of the time (any of two
/// requests and two answers lost); six failures in a row, 4e-9 per step, are about one start in
/// a million of six drives' 45 steps (with three repeats, one in 1400: can_bench's soak saw one
/// in 2000 restarts).
pub const START_RETRIES: u8 = 5;

/// When a start step's frames went out, and how often they were repeated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Retry {
    /// The cycle of the last send.
    sent_at: u32,
    /// Repeats of the current step so far.
    repeats: u8,
}

impl Retry {
    /// A new step's frames went out in `cycle`.
    pub fn sent(&mut self, cycle: u32) {
        *self = Self {
            sent_at: cycle,
            repeats: 0,
        };
    }

    /// True if the step's frames are due again at `cycle`: unanswered for `timeout` cycles
    /// (the drive's link faults one cycle later) with repeats left. Counts the repeat.
    pub fn due(&mut self, cycle: u32, timeout: u32) -> bool {
        let due = cycle.wrapping_sub(self.sent_at) >= timeout && self.repeats < START_RETRIES;
        if due {
            self.sent_at = cycle;
            self.repeats = self.repeats.saturating_add(1);
        }
        due
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn due_after_each_timeout_until_the_retries_are_spent() {
        let mut retry = Retry::default();
        retry.sent(100);
        assert!(!retry.due(109, 10));
        let repeats: Vec<u32> = (110..200).filter(|&c| retry.due(c, 10)).collect();
        assert_eq!(repeats, [110, 120, 130, 140, 150]);
        // A new step: five more.
        retry.sent(200);
        assert!(retry.due(210, 10));
    }
}
