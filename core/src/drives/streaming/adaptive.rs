//! The PDO schedule's adaptive lead, like an adaptive jitter buffer: the robot file's lead on
//! a clean bus, more while points are being lost, back down after a quiet interval.
//!
//! A lost receive PDO leaves its drive one point short until the report that shows it is read,
//! two SYNCs later; a lead that covers every loss in that window costs latency all the time.
//! Instead the stream keeps `drives.pdo_lead` until a report shows points lost (or a report is
//! missing: a lost SYNC or transmit PDO, not a lost point, but the bus losing frames), raises
//! the lead by one per cycle that shows a loss up to `drives.pdo_lead_raise` above it, holds it
//! while losses continue, and lowers it by one after each quiet interval without one.
//!
//! What it cannot do: a point lost while a drive sits at its least lead underflows that drive
//! before any report can show the loss, so the first loss after a quiet interval may cost one
//! underflow; only a higher `drives.pdo_lead` prevents that (docs/drives.md, "The lead").
//!
//! A change is one set-point of time stretch (raise: every drive gets one point more that
//! cycle, an interpolated one) or compression (lower: every drive one point less), on every
//! drive in the same cycle, so the joints stay in step.

/// The most points the stream raises the lead by default (`DriveSettings::pdo_lead_raise`):
/// the default lead 2 raised to 4, which streamed the 10-minute soak with 1 % of the frames
/// lost without an underflow as a fixed lead.
pub const PDO_LEAD_RAISE: u16 = 3;

/// Points a start or restart that saw the bus lose frames raises the lead by at once: a
/// stream begun one higher still lost a point with no spare in 2 of 20 one-minute runs at 1 %
/// loss where two higher did not (docs/drives.md, "The lead"); streaming on, the lead settles
/// at 5 under such loss anyway.
pub const START_RAISE: u16 = 2;

/// What every drive's stream does with its lead this cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LeadChange {
    /// Keep it.
    Hold,
    /// One point more beyond the read pointer from now on.
    Raise,
    /// One point less.
    Lower,
}

impl LeadChange {
    /// Points the lead moves by: +1, 0 or −1.
    pub fn step(self) -> i8 {
        match self {
            Self::Hold => 0,
            Self::Raise => 1,
            Self::Lower => -1,
        }
    }
}

/// The lead policy shared by all drives on the bus.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AdaptiveLead {
    /// The most the lead may be raised above the robot file's (0: never).
    raise_max: u16,
    /// Cycles without a loss before the lead comes down by one (at least 1).
    quiet_cycles: u32,
    /// Points the lead is raised now.
    raised: u16,
    /// Cycles since the last loss or the last change down.
    quiet: u32,
    /// A loss seen since the last cycle.
    seen: bool,
}

impl AdaptiveLead {
    /// A policy that may raise the lead by up to `raise_max` points and lowers it by one after
    /// every `quiet_cycles` cycles without a loss.
    pub fn new(raise_max: u16, quiet_cycles: u32) -> Self {
        Self {
            raise_max,
            quiet_cycles: quiet_cycles.max(1),
            raised: 0,
            quiet: 0,
            seen: false,
        }
    }

    /// A report showed points lost (or another sign that the bus loses frames).
    pub fn saw_loss(&mut self) {
        self.seen = true;
    }

    /// The drives start (again, after a fault) or begin streaming: a loss seen since the last
    /// cycle (the one that made the fault, or a start request whose answer was lost) raises the
    /// lead the new streams begin with, by [`START_RAISE`] (within the most).
    pub fn restart(&mut self) {
        if core::mem::take(&mut self.seen) && self.raised < self.raise_max {
            self.raised = self.raised.saturating_add(START_RAISE).min(self.raise_max);
            self.quiet = 0;
        }
    }

    /// One streaming cycle, after its reports were read. Returns what every drive's stream
    /// does with its lead in this cycle.
    pub fn cycle(&mut self) -> LeadChange {
        if core::mem::take(&mut self.seen) {
            self.quiet = 0;
            if self.raised < self.raise_max {
                self.raised += 1;
                return LeadChange::Raise;
            }
            return LeadChange::Hold;
        }
        self.quiet = self.quiet.saturating_add(1);
        if self.raised > 0 && self.quiet >= self.quiet_cycles {
            self.raised -= 1;
            self.quiet = 0;
            return LeadChange::Lower;
        }
        LeadChange::Hold
    }

    /// Points the lead is raised above the robot file's now.
    pub fn raised(&self) -> u16 {
        self.raised
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn raises_one_per_loss_up_to_the_limit_and_lowers_one_per_quiet_interval() {
        let mut lead = AdaptiveLead::new(2, 3);
        let mut cycle = |lost: bool| {
            if lost {
                lead.saw_loss();
            }
            lead.cycle()
        };
        use LeadChange::{Hold, Lower, Raise};
        let changes = [false, true, true, true].map(&mut cycle);
        assert_eq!(changes, [Hold, Raise, Raise, Hold]);
        // Two quiet cycles, a loss: the quiet interval starts again.
        let changes = [
            false, false, true, false, false, false, false, false, false, false,
        ];
        assert_eq!(
            changes.map(&mut cycle),
            [Hold, Hold, Hold, Hold, Hold, Lower, Hold, Hold, Lower, Hold]
        );
        assert_eq!(lead.raised(), 0);
    }

    #[test]
    fn a_loss_before_a_restart_raises_the_lead_the_streams_begin_with() {
        let mut lead = AdaptiveLead::new(3, 3);
        lead.restart();
        assert_eq!(lead.raised(), 0);
        lead.saw_loss();
        lead.restart();
        assert_eq!(lead.raised(), START_RAISE);
        // Taken: the first cycle holds.
        assert_eq!(lead.cycle(), LeadChange::Hold);
        // Within the most the lead may be raised.
        lead.saw_loss();
        lead.restart();
        assert_eq!(lead.raised(), 3);
    }

    #[test]
    fn a_limit_of_zero_never_changes_the_lead() {
        let mut lead = AdaptiveLead::new(0, 1);
        for lost in [true, false, true, true, false, false] {
            if lost {
                lead.saw_loss();
            }
            assert_eq!(lead.cycle(), LeadChange::Hold);
        }
    }
}
