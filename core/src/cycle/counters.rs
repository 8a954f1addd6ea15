//! What the cycle counted.

/// Counters since the cycle was made (they saturate; none of them is a fault by itself).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CycleCounters {
    /// Ticks run.
    pub ticks: u64,
    /// Ticks run a whole period or more late (caught up back to back).
    pub late_ticks: u64,
    /// Ticks skipped because the shell was more than `MAX_CATCH_UP` periods late.
    pub skipped_ticks: u64,
    /// Client requests handled.
    pub requests: u64,
    /// Ticks whose control step refused the measurement (the drives held), and ticks in which
    /// a simulated bus stalled.
    pub tick_errors: u64,
    /// Notices sent to a client.
    pub notices: u64,
    /// Notices dropped because no client had sent a request yet.
    pub notices_unaddressed: u64,
    /// Replies and notices the link could not send.
    pub send_dropped: u64,
}

/// Adds one to `counter`, saturating.
pub(super) fn bump(counter: &mut u64) {
    *counter = counter.saturating_add(1);
}
