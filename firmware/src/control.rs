//! The control task: the core's tick at the robot's control period, on the high-priority
//! interrupt executor.
//!
//! It owns the core's state — the [`CommandHandler`] and the drives (the CANopen drive manager
//! and its bus, [`BoardDrives`]) — and does what `armgate-sim` does with them, with the
//! queues of [`crate::link`] in place of a socket (one difference: a tick the core refuses,
//! because the measurement does not fit the arm, makes `armgate-sim` exit with the reason,
//! while the board holds and counts it in the status line). Each tick:
//!
//! 1. handles every request waiting in [`REQUESTS`] (at most [`REQUEST_QUEUE`]) with
//!    [`CommandHandler::handle`] and queues each reply to its sender;
//! 2. the drive manager takes what the bus received ([`BoardDrives::receive`]), runs
//!    [`CommandHandler::tick`] on the measured joints, and the manager queues the cycle's
//!    frames ([`BoardDrives::transmit`]: set-points, queries, heartbeat; never waits on the bus);
//! 3. queues the unsolicited notices to the last sender;
//! 4. feeds the independent watchdog. Nothing else feeds it: if a tick does not finish within
//!    [`watchdog_timeout`], the board resets.
//!
//! The core's clock is the tick's scheduled time since start-up, as in `armgate-sim`: the core
//! computes the same results on the host and on the board. A tick that starts more than one
//! period late restarts the schedule (the core never catches up by running ticks back to back).

use armgate_core::command::{CommandHandler, NOTICE_CAPACITY};
use armgate_core::config::ValidRobot;
use embassy_net::IpEndpoint;
use embassy_stm32::peripherals::IWDG1;
use embassy_stm32::wdg::IndependentWatchdog;
use embassy_time::{Duration, Instant, Timer};

use crate::drives::BoardDrives;
use crate::link::{COUNTERS, Datagram, OUTGOING, REQUEST_QUEUE, REQUESTS, count};
use crate::telemetry::{STATUS, Status};

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
    overruns: u32,
    tick_errors: u32,
    requests: u32,
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

    fn status(&self, handler: &CommandHandler, drives: &BoardDrives) -> Status {
        let controller = handler.controller();
        let saturate = |v: u64| u32::try_from(v).unwrap_or(u32::MAX);
        Status {
            mode: controller.mode(),
            moving: controller.is_moving(),
            position: controller
                .measured()
                .map(|(_, pose)| pose.translation.vector.into()),
            ticks: self.ticks,
            overruns: self.overruns,
            tick_errors: self.tick_errors,
            requests: self.requests,
            compute_mean_us: saturate(self.compute_total_us / u64::from(self.ticks.max(1))),
            compute_max_us: saturate(self.compute_max_us),
            wake_latency_max_us: saturate(self.wake_latency_max_us),
            relay_dropped: handler.dropped_notices(),
            drives: drives.manager().state(),
            fault: drives.manager().fault().map(|f| f.text()),
        }
    }
}

/// The control task: one tick every `robot.control_period`, forever. Starts the watchdog.
#[embassy_executor::task]
pub async fn run(
    robot: &'static ValidRobot,
    mut drives: BoardDrives,
    mut watchdog: IndependentWatchdog<'static, IWDG1>,
) {
    let period = period(robot);
    defmt::info!(
        "control: {} ({} joints), period {} us, watchdog {} ms",
        robot.name.as_str(),
        robot.dof(),
        period.as_micros(),
        watchdog_timeout(period).as_millis()
    );
    let mut handler = CommandHandler::new(robot);
    let mut last_sender: Option<IpEndpoint> = None;
    let mut interval = Interval::default();
    let epoch = Instant::now();
    let mut scheduled = epoch;
    let mut next_report = epoch + REPORT_INTERVAL;
    watchdog.unleash();
    loop {
        Timer::at(scheduled).await;
        let begin = Instant::now();
        let now = (scheduled - epoch).as_micros() as f64 * 1e-6;

        interval.requests += handle_requests(&mut handler, &mut drives, &mut last_sender);
        if !drives.receive(now) {
            // The simulated bus stalled (`sim-drives`): the manager's timeouts will fault.
            interval.tick_errors += 1;
        }
        match handler.tick(now, &drives.measured(), drives.manager()) {
            Ok(out) => drives.transmit(now, out.command.as_ref()),
            Err(_) => {
                // The measurement does not fit the arm: hold, and say so in the status line.
                interval.tick_errors += 1;
                drives.transmit(now, None);
            }
        }
        send_notices(&mut handler, last_sender);
        watchdog.pet();

        let end = Instant::now();
        interval.add(begin - scheduled, end - begin);
        scheduled += period;
        if scheduled < end {
            interval.overruns += 1;
            scheduled = end + period;
        }
        if begin >= next_report {
            STATUS.signal(interval.status(&handler, &drives));
            interval = Interval::default();
            next_report += REPORT_INTERVAL;
        }
    }
}

/// Handles the waiting requests (at most [`REQUEST_QUEUE`]: later ones wait for the next tick,
/// so a tick's work stays bounded) and queues their replies; returns how many it handled.
fn handle_requests(
    handler: &mut CommandHandler,
    drives: &mut BoardDrives,
    last_sender: &mut Option<IpEndpoint>,
) -> u32 {
    let mut handled = 0;
    for _ in 0..REQUEST_QUEUE {
        let Ok(request) = REQUESTS.try_receive() else {
            break;
        };
        let reply = handler.handle(request.payload(), drives.manager_mut());
        *last_sender = Some(request.peer);
        post(Datagram::new(&reply, request.peer));
        handled += 1;
    }
    handled
}

/// Queues the core's unsolicited notices to the last sender (at most as many as its relay
/// holds, which [`OUTGOING_QUEUE`](crate::link::OUTGOING_QUEUE) has room for).
fn send_notices(handler: &mut CommandHandler, last_sender: Option<IpEndpoint>) {
    for _ in 0..NOTICE_CAPACITY {
        let Some(text) = handler.next_notice() else {
            break;
        };
        match last_sender {
            Some(peer) => post(Datagram::new(&text.to_bytes(), peer)),
            None => count(&COUNTERS.notices_unaddressed),
        }
    }
}

/// Queues one datagram for the UDP server, or counts it as dropped.
fn post(datagram: Datagram) {
    if OUTGOING.try_send(datagram).is_err() {
        count(&COUNTERS.outgoing_full);
    }
}
