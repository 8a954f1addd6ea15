//! The once-per-second status line.
//!
//! The control task publishes a [`Status`] snapshot once per second through [`STATUS`]; this
//! task, on the thread executor, writes it to the defmt log together with the queue counters,
//! so that formatting and the RTT write never run on the control tick.

use armgate_core::drives::DriveState;
use armgate_core::motion::Mode;
use armgate_protocol::client::Text;
use armgate_protocol::client::signed::SigningReport;
use embassy_net::Stack;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::signal::Signal;

#[cfg(all(target_os = "none", not(feature = "sim-drives")))]
use crate::can::CAN_COUNTERS;
use crate::link::{COUNTERS, read};

/// One report interval of the control task.
#[derive(Clone, Copy)]
pub struct Status {
    /// The control mode at the end of the interval.
    pub mode: Mode,
    /// Whether a motion or sequence was running.
    pub moving: bool,
    /// Measured tool position (m), if a tick has run.
    pub position: Option<[f64; 3]>,
    /// Ticks in the interval.
    pub ticks: u32,
    /// Ticks run a period or more late, or skipped, since boot (the cycle's policy).
    pub overruns: u32,
    /// Ticks whose measurement the core refused (the arm held), since boot.
    pub tick_errors: u32,
    /// Requests handled since boot.
    pub requests: u32,
    /// Notices dropped because no client had sent a request yet, since boot.
    pub notices_unaddressed: u32,
    /// Compute time per tick (the whole cycle tick), mean and maximum (µs).
    pub compute_mean_us: u32,
    /// See `compute_mean_us`.
    pub compute_max_us: u32,
    /// Largest delay between a tick's scheduled time and its start (µs).
    pub wake_latency_max_us: u32,
    /// Notices the core's relay dropped since boot (its outbox was full).
    pub relay_dropped: u32,
    /// What the drive manager is doing.
    pub drives: DriveState,
    /// Its fault (the client's `ER3x` text), if any.
    pub fault: Option<Text>,
    /// The signature checks since boot (`SQ` index 4).
    pub signing: SigningReport,
}

/// The latest snapshot; a new one replaces an unread one.
pub static STATUS: Signal<CriticalSectionRawMutex, Status> = Signal::new();

/// The status task: one log line per snapshot.
#[embassy_executor::task]
pub async fn run(stack: Stack<'static>) {
    loop {
        let s = STATUS.wait().await;
        let [x, y, z] = s.position.unwrap_or([f64::NAN; 3]);
        let fault = s.fault.as_ref().map_or("no fault", Text::as_str);
        #[cfg(all(target_os = "none", not(feature = "sim-drives")))]
        defmt::info!(
            "can: {} bus errors, {} foreign frames, {} bus-off recoveries",
            read(&CAN_COUNTERS.bus_errors),
            read(&CAN_COUNTERS.foreign_frames),
            read(&CAN_COUNTERS.bus_offs),
        );
        defmt::info!(
            "signing: {} signed, {} unsigned served; dropped {} unsigned, {} truncated, {} forged, {} replayed",
            s.signing.signed,
            s.signing.unsigned,
            s.signing.dropped_unsigned,
            s.signing.dropped_truncated,
            s.signing.dropped_forged,
            s.signing.dropped_replayed,
        );
        defmt::info!(
            "status: link {}, {} {}, drives {=str} ({=str}), xyz {=f64} {=f64} {=f64} m | {} ticks, {} overruns, {} errors, compute mean {} us max {} us, wake latency max {} us | {} requests; rx {} dropped: {} in the stack, {} foreign, {} queue full, {} replies full, {} unaddressed, {} send errors, {} unreachable, {} relay",
            if stack.is_link_up() { "up" } else { "down" },
            s.mode.name(),
            if s.moving { "moving" } else { "holding" },
            drive_state_name(s.drives),
            fault,
            x,
            y,
            z,
            s.ticks,
            s.overruns,
            s.tick_errors,
            s.compute_mean_us,
            s.compute_max_us,
            s.wake_latency_max_us,
            s.requests,
            read(&COUNTERS.received),
            read(&COUNTERS.stack_dropped),
            read(&COUNTERS.foreign),
            read(&COUNTERS.requests_full),
            read(&COUNTERS.outgoing_full),
            s.notices_unaddressed,
            read(&COUNTERS.send_errors),
            read(&COUNTERS.unreachable),
            s.relay_dropped,
        );
    }
}

/// The drive manager's state, for the status line.
fn drive_state_name(state: DriveState) -> &'static str {
    match state {
        DriveState::Idle => "idle",
        DriveState::Starting => "starting",
        DriveState::Operational => "operational",
        DriveState::Stopping => "stopping",
        DriveState::Stopped => "stopped",
        DriveState::Faulted => "faulted",
    }
}
