//! The status line on the terminal and the summary at exit.

use armgate_core::command::Status;
use armgate_core::cycle::CycleCounters;
use armgate_protocol::client::DriveStatus;
use armgate_protocol::client::signed::{SigningPolicy, SigningReport};

use crate::SimCycle;
use crate::log::Logger;
use crate::udp::Stats;

/// What the drives do, as the status line shows it: `running`, `starting`, `off`,
/// `faulted ER31`.
pub fn drive_state(status: &Status) -> String {
    let state = match status.drives {
        DriveStatus::Off => "off",
        DriveStatus::Starting => "starting",
        DriveStatus::Running => "running",
        DriveStatus::Stopping => "stopping",
        DriveStatus::Faulted => "faulted",
    };
    match status.fault {
        Some(code) => format!("{state} ER{code:02}"),
        None => state.to_owned(),
    }
}

/// The core's status snapshot (what `SQ` reports).
pub fn snapshot(cycle: &SimCycle) -> Status {
    cycle.handler().status(cycle.drives())
}

/// One status line: mode, drives, motion, pose, counters (from the core's status snapshot).
pub fn line(cycle: &SimCycle, stats: &Stats, logger: &Logger) -> String {
    let status = snapshot(cycle);
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
    let signing = cycle.signing();
    let signing = match signing.policy {
        Some(SigningPolicy::Off) | None => String::new(),
        Some(_) => format!(
            " signed {} unverified {}",
            signing.signed,
            signing.dropped()
        ),
    };
    format!(
        "mode {:<9} drives {:<8} {motion:<7} {pose} | rx {} refused {} denied {}{signing} warnings {} log dropped {}",
        ctrl.mode().name(),
        drive_state(&status),
        stats.received,
        status.refused,
        stats.refused_sources,
        cycle.counters().notices,
        logger.dropped()
    )
}

/// The line printed at exit. Ticks skipped in a stall are counted as the ticks they are (a 2 s
/// stall at 19.44 ms misses about 100), not as one overrun.
/// `refused` is the core's count of refused requests.
pub fn summary(stats: &Stats, refused: u32, counters: &CycleCounters, log_dropped: u64) -> String {
    format!(
        "{} datagrams handled ({} refused), {} from sources not allowed (dropped), \
         {} over the inbox's capacity (dropped), {} warnings sent, {} ticks late (caught up), {} ticks missed (skipped), \
         {} tick errors, {} log records dropped",
        stats.received,
        refused,
        stats.refused_sources,
        stats.crowded,
        counters.notices,
        counters.late_ticks,
        counters.skipped_ticks,
        counters.tick_errors,
        log_dropped
    )
}

/// The signing line printed at exit: the policy, what was served, what was dropped by cause.
pub fn signing(report: &SigningReport) -> String {
    let policy = match report.policy {
        Some(SigningPolicy::Off) | None => {
            return format!(
                "signing off (no key), {} datagrams unsigned",
                report.unsigned
            );
        }
        Some(SigningPolicy::Required) => "signing required",
        Some(SigningPolicy::UnsignedRead) => "signing required, unsigned may read",
        Some(SigningPolicy::UnsignedAll) => "signing on, unsigned allowed",
    };
    format!(
        "{policy}: {} signed and {} unsigned datagrams served; dropped: {} unsigned, \
         {} truncated, {} forged, {} replayed",
        report.signed,
        report.unsigned,
        report.dropped_unsigned,
        report.dropped_truncated,
        report.dropped_forged,
        report.dropped_replayed
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_summary_counts_refusals_and_missed_ticks() {
        let stats = Stats {
            received: 5,
            refused_sources: 1,
            crowded: 0,
        };
        let counters = CycleCounters {
            skipped_ticks: 103,
            late_ticks: 50,
            ..CycleCounters::default()
        };
        let s = summary(&stats, 2, &counters, 0);
        assert!(
            s.starts_with("5 datagrams handled (2 refused), 1 from"),
            "{s}"
        );
        assert!(
            s.contains("50 ticks late (caught up), 103 ticks missed (skipped)"),
            "{s}"
        );
    }

    #[test]
    fn the_signing_line_counts_by_cause() {
        let report = SigningReport {
            policy: Some(SigningPolicy::Required),
            signed: 9,
            dropped_forged: 2,
            dropped_replayed: 1,
            ..SigningReport::default()
        };
        assert_eq!(
            signing(&report),
            "signing required: 9 signed and 0 unsigned datagrams served; dropped: 0 unsigned, \
             0 truncated, 2 forged, 1 replayed"
        );
        assert_eq!(
            signing(&SigningReport::default()),
            "signing off (no key), 0 datagrams unsigned"
        );
    }

    #[test]
    fn the_drive_state_shows_its_fault() {
        let status = Status {
            mode: armgate_protocol::client::Mode::Off,
            drives: DriveStatus::Faulted,
            fault: Some(31),
            joints: 6,
            motion: armgate_protocol::client::Motion::Holding,
            refused: 2,
            uptime: 1.0,
        };
        assert_eq!(drive_state(&status), "faulted ER31");
    }
}
