//! Whether a drive still answers: a counted timeout on its outstanding requests.

/// The requests sent to one drive and not yet answered.
///
/// A drive is silent when it has left requests unanswered for more than the timeout without
/// answering anything at all. A single lost reply therefore does not fault a drive that keeps
/// answering later requests; a drive that stops answering is caught within the timeout (the
/// seed only warned about unanswered `PX` queries and kept the stale value, §9 item 34).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Link {
    outstanding: u32,
    /// The cycle since which the drive owes an answer.
    waiting_since: Option<u32>,
}

impl Link {
    /// A request went out in `cycle`.
    pub fn sent(&mut self, cycle: u32) {
        if self.outstanding == 0 {
            self.waiting_since = Some(cycle);
        }
        self.outstanding = self.outstanding.saturating_add(1);
    }

    /// An answer arrived in `cycle`.
    pub fn heard(&mut self, cycle: u32) {
        self.outstanding = self.outstanding.saturating_sub(1);
        self.waiting_since = (self.outstanding > 0).then_some(cycle);
    }

    /// The requests still owed were sent again in `cycle`: `outstanding` are owed (the lost
    /// ones are forgotten), and the timeout starts over.
    pub fn resent(&mut self, outstanding: u32, cycle: u32) {
        self.outstanding = outstanding;
        self.waiting_since = (outstanding > 0).then_some(cycle);
    }

    /// True if the drive has owed an answer for more than `timeout` cycles at `cycle`.
    pub fn silent(&self, cycle: u32, timeout: u32) -> bool {
        self.waiting_since
            .is_some_and(|since| cycle.wrapping_sub(since) > timeout)
    }
}
