//! The status line on the terminal and the summary at exit.

use std::net::SocketAddr;

use armgate_core::command::Drives;
use armgate_core::cycle::{Cycle, CycleCounters};
use armgate_core::drives::DriveState;

use crate::backend::Backend;
use crate::log::Logger;
use crate::udp::Stats;

/// What the drives do, as the status line shows it: `running`, `starting`, `off`,
/// `faulted ER31 …`.
pub fn drive_state(drives: &Backend) -> String {
    if let Some(fault) = drives.fault() {
        return format!("faulted {}", fault.as_str());
    }
    match drives.state() {
        Some(DriveState::Idle | DriveState::Stopped) => "off".into(),
        Some(DriveState::Starting) => "starting".into(),
        Some(DriveState::Operational) => "running".into(),
        Some(DriveState::Stopping) => "stopping".into(),
        Some(DriveState::Faulted) => "faulted".into(),
        None if drives.is_operational() => "running".into(),
        None => "off".into(),
    }
}

/// One status line: mode, drives, motion, pose, counters.
pub fn line(cycle: &Cycle<Backend, SocketAddr>, stats: &Stats, logger: &Logger) -> String {
    let ctrl = cycle.handler().controller();
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
        "mode {:<9} drives {:<8} {motion:<7} {pose} | rx {} refused {} denied {} warnings {} log dropped {}",
        ctrl.mode().name(),
        drive_state(cycle.drives()),
        stats.received,
        stats.refused,
        stats.refused_sources,
        cycle.counters().notices,
        logger.dropped()
    )
}

/// The line printed at exit. Ticks skipped in a stall are counted as the ticks they are (a 2 s
/// stall at 19.44 ms misses about 100), not as one overrun.
pub fn summary(stats: &Stats, counters: &CycleCounters, log_dropped: u64) -> String {
    format!(
        "{} datagrams handled ({} refused), {} from sources not allowed (dropped), \
         {} warnings sent, {} ticks late (caught up), {} ticks missed (skipped), \
         {} tick errors, {} log records dropped",
        stats.received,
        stats.refused,
        stats.refused_sources,
        counters.notices,
        counters.late_ticks,
        counters.skipped_ticks,
        counters.tick_errors,
        log_dropped
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_summary_counts_refusals_and_missed_ticks() {
        let stats = Stats {
            received: 5,
            refused: 2,
            refused_sources: 1,
        };
        let counters = CycleCounters {
            skipped_ticks: 103,
            late_ticks: 50,
            ..CycleCounters::default()
        };
        let s = summary(&stats, &counters, 0);
        assert!(
            s.starts_with("5 datagrams handled (2 refused), 1 from"),
            "{s}"
        );
        assert!(
            s.contains("50 ticks late (caught up), 103 ticks missed (skipped)"),
            "{s}"
        );
    }
}
