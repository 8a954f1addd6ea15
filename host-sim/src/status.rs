//! The status line on the terminal and the counters behind it and the exit summary.

use std::time::Duration;

use armgate_core::command::CommandHandler;
use armgate_core::drives::DriveState;

use crate::backend::Backend;
use crate::log::Logger;

/// Counters shown in the status line and at exit.
#[derive(Debug, Default)]
pub struct Stats {
    /// Datagrams handled.
    pub received: u64,
    /// Requests answered with an `ER` text (refused).
    pub refused: u64,
    /// Datagrams dropped because their source is not on the allow-list.
    pub denied_sources: u64,
    /// Unsolicited warnings sent.
    pub notices: u64,
    /// Ticks that never ran because the loop was too far behind (a stall).
    pub missed_ticks: u64,
    /// How many times the loop gave up catching up.
    pub stalls: u64,
}

impl Stats {
    /// Counts a reply: an `ER` text is a refusal.
    pub fn count_reply(&mut self, reply: &[u8]) {
        if reply.starts_with(b"ER") {
            self.refused += 1;
        }
    }

    /// Counts a stall of `behind` beyond the tick that was due, with ticks every `period`:
    /// every tick due in that time is missed (the loop resumes one period later).
    pub fn count_stall(&mut self, behind: Duration, period: Duration) {
        self.stalls += 1;
        self.missed_ticks += missed_ticks(behind, period);
    }

    /// The line printed at exit.
    pub fn summary(&self, log_dropped: u64) -> String {
        format!(
            "{} datagrams handled ({} refused), {} from sources not allowed (dropped), \
             {} warnings sent, {} ticks missed in {} stalls, {} log records dropped",
            self.received,
            self.refused,
            self.denied_sources,
            self.notices,
            self.missed_ticks,
            self.stalls,
            log_dropped
        )
    }
}

/// The ticks due within `behind` after a due tick, that one included.
pub fn missed_ticks(behind: Duration, period: Duration) -> u64 {
    if period.is_zero() {
        return 0;
    }
    let whole = behind.as_nanos() / period.as_nanos();
    u64::try_from(whole).unwrap_or(u64::MAX).saturating_add(1)
}

/// What the drives do, as the status line shows it: `running`, `starting`, `off`,
/// `faulted ER31 …`.
pub fn drive_state(drives: &Backend) -> String {
    if let Some(fault) = drives.drives().fault() {
        return format!("faulted {}", fault.as_str());
    }
    match drives.state() {
        Some(DriveState::Idle | DriveState::Stopped) => "off".into(),
        Some(DriveState::Starting) => "starting".into(),
        Some(DriveState::Operational) => "running".into(),
        Some(DriveState::Stopping) => "stopping".into(),
        Some(DriveState::Faulted) => "faulted".into(),
        None if drives.drives().is_operational() => "running".into(),
        None => "off".into(),
    }
}

/// One status line: mode, drives, motion, pose, counters.
pub fn line(handler: &CommandHandler, drives: &Backend, stats: &Stats, logger: &Logger) -> String {
    let ctrl = handler.controller();
    let pose = ctrl
        .measured()
        .map(|(_, p)| {
            let [x, y, z]: [f64; 3] = p.translation.vector.into();
            format!("x {x:+.4} y {y:+.4} z {z:+.4}")
        })
        .unwrap_or_default();
    let motion = if ctrl.is_moving() {
        "moving"
    } else {
        "holding"
    };
    format!(
        "mode {:<5} drives {:<8} {motion:<7} {pose} | rx {} refused {} denied {} warnings {} log dropped {}",
        ctrl.mode().name(),
        drive_state(drives),
        stats.received,
        stats.refused,
        stats.denied_sources,
        stats.notices,
        logger.dropped()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_two_second_stall_misses_its_ticks() {
        let period = Duration::from_micros(19_440);
        // The loop gives up catching up 50 periods late; 2 s late means 103 ticks never ran.
        assert_eq!(missed_ticks(Duration::from_secs(2), period), 103);
        assert_eq!(missed_ticks(Duration::ZERO, period), 1);
        assert_eq!(missed_ticks(Duration::from_secs(1), Duration::ZERO), 0);
        let mut stats = Stats::default();
        stats.count_stall(Duration::from_secs(2), period);
        assert!(stats.summary(0).contains("103 ticks missed in 1 stalls"));
    }

    #[test]
    fn error_replies_are_refusals() {
        let mut stats = Stats::default();
        stats.count_reply(b"ER20 Cmd BG rejected\0");
        stats.count_reply(b"GB\0\0");
        stats.count_reply(b"WN12 Joint limit.");
        assert_eq!(stats.refused, 1);
    }
}
