//! The control task: the core's [`Cycle`] at the robot's control period, on the high-priority
//! interrupt executor.
//!
//! It owns the cycle — the command handler and the drives ([`BoardDrives`]: the CANopen drive
//! manager on its bus) — and is a thin shell around it, as `armgate-sim` is: it waits for the
//! next tick on the schedule, runs [`Cycle::tick`] with the queues of [`crate::link`] as the
//! client port ([`QueueLink`]), and feeds the independent watchdog. Nothing else feeds it: if
//! a tick does not finish within [`watchdog_timeout`], the board resets. The policy — late
//! ticks, requests per tick, notices, bus-off — is the core's, described in
//! `armgate_core::cycle` and docs/architecture.md.

use armgate_core::config::ValidRobot;
use armgate_core::cycle::{Cycle, Datagram, Dropped, Link, Outgoing, Signing};
use core::net::SocketAddr;

use embassy_time::{Duration, Instant, Timer};

use crate::board::{ReplayStore, Watchdog};
use crate::drives::BoardDrives;
use crate::link::{COUNTERS, OUTGOING, count, read, set_holder, take};
use crate::telemetry::{STATUS, Status};

/// The cycle as the board runs it.
type BoardCycle = Cycle<BoardDrives, SocketAddr, ReplayStore>;

/// Interval between two status snapshots.
const REPORT_INTERVAL: Duration = Duration::from_secs(1);
/// The watchdog timeout is this many control periods, but at least [`MIN_WATCHDOG_TIMEOUT`].
const WATCHDOG_PERIODS: u32 = 4;
/// The shortest watchdog timeout.
const MIN_WATCHDOG_TIMEOUT: Duration = Duration::from_millis(100);

/// The control period of `robot` as an embassy duration (whole microseconds, at least 1 µs).
pub fn period(robot: &ValidRobot) -> Duration {
    // The period is validated finite and positive; the cast saturates for absurd values.
    let micros = libm::round(robot.control_period * 1e6) as u64;
    Duration::from_micros(micros.max(1))
}

/// The independent watchdog's timeout for a control period: [`WATCHDOG_PERIODS`] periods, at
/// least [`MIN_WATCHDOG_TIMEOUT`] (the IWDG's 32 kHz clock is only good to a few per cent, and
/// a tick must be able to be late by a period without resetting the board).
pub fn watchdog_timeout(period: Duration) -> Duration {
    (period * WATCHDOG_PERIODS).max(MIN_WATCHDOG_TIMEOUT)
}

/// Statistics over one report interval.
#[derive(Default)]
struct Interval {
    ticks: u32,
    compute_total_us: u64,
    compute_max_us: u64,
    wake_latency_max_us: u64,
}

impl Interval {
    fn add(&mut self, latency: Duration, compute: Duration) {
        self.ticks += 1;
        self.compute_total_us += compute.as_micros();
        self.compute_max_us = self.compute_max_us.max(compute.as_micros());
        self.wake_latency_max_us = self.wake_latency_max_us.max(latency.as_micros());
    }

    fn status(&self, cycle: &BoardCycle) -> Status {
        let controller = cycle.handler().controller();
        let counters = cycle.counters();
        let saturate = |v: u64| u32::try_from(v).unwrap_or(u32::MAX);
        let manager = cycle.drives().manager();
        Status {
            mode: controller.mode(),
            moving: controller.is_moving(),
            position: controller
                .measured()
                .map(|(_, pose)| pose.translation.vector.into()),
            ticks: self.ticks,
            overruns: saturate(counters.late_ticks + counters.skipped_ticks),
            tick_errors: saturate(counters.tick_errors),
            requests: saturate(counters.requests),
            notices_unaddressed: saturate(counters.notices_unaddressed),
            compute_mean_us: saturate(self.compute_total_us / u64::from(self.ticks.max(1))),
            compute_max_us: saturate(self.compute_max_us),
            wake_latency_max_us: saturate(self.wake_latency_max_us),
            relay_dropped: cycle.handler().dropped_notices(),
            drives: manager.state(),
            fault: manager.fault().map(|f| f.text()),
            signing: cycle.signing(),
        }
    }
}

/// The control task: one tick every `robot.control_period`, forever, checking signatures as
/// `signing` says and keeping the replay reservation in `store`. Starts the watchdog.
#[embassy_executor::task]
pub async fn run(
    robot: &'static ValidRobot,
    drives: BoardDrives,
    mut watchdog: Watchdog,
    signing: (Signing, ReplayStore),
) {
    let (signing, store) = signing;
    let period = period(robot);
    defmt::info!(
        "control: {} ({} joints), period {} us, watchdog {} ms",
        robot.name.as_str(),
        robot.dof(),
        period.as_micros(),
        watchdog_timeout(period).as_millis()
    );
    match &signing.key {
        Some(key) => defmt::info!(
            "signing: required for controller {=u32:08x} (unsigned: {})",
            key.controller().0,
            defmt::Display2Format(&signing.unsigned)
        ),
        None => defmt::info!("signing: off (no key): every datagram is served unsigned"),
    }
    let mut cycle: BoardCycle = Cycle::new(robot, drives)
        .with_store(store)
        .with_signing(signing);
    let mut interval = Interval::default();
    let epoch = Instant::now();
    let mut next_report = epoch + REPORT_INTERVAL;
    watchdog.unleash();
    loop {
        let scheduled = epoch + Duration::from_micros(cycle.next_due_us());
        Timer::at(scheduled).await;
        let begin = Instant::now();
        cycle.tick((begin - epoch).as_micros(), &mut QueueLink);
        set_holder(cycle.holder().map(|holder| holder.ip()));
        watchdog.pet();
        let end = Instant::now();
        interval.add(begin.saturating_duration_since(scheduled), end - begin);
        if begin >= next_report {
            STATUS.signal(interval.status(&cycle));
            interval = Interval::default();
            next_report += REPORT_INTERVAL;
        }
    }
}

/// The queues of [`crate::link`] as the cycle's client port.
struct QueueLink;

impl Link<SocketAddr> for QueueLink {
    fn receive(&mut self) -> Option<Datagram<SocketAddr>> {
        take()
    }

    /// A full queue drops the datagram and counts it.
    fn send(&mut self, datagram: &Datagram<SocketAddr>, _kind: Outgoing) -> Result<(), Dropped> {
        OUTGOING.try_send(*datagram).map_err(|_| {
            count(&COUNTERS.outgoing_full);
            Dropped
        })
    }

    /// Replies and notices the UDP server dropped: destinations that did not resolve, and what
    /// the stack refused.
    fn dropped(&self) -> u64 {
        u64::from(read(&COUNTERS.unreachable)) + u64::from(read(&COUNTERS.send_errors))
    }
}
