//! `armgate-sim --whistles --can socketcan:IFACE`: the robot file's simulated Whistles as a
//! process on a CAN interface, for a controller on the other side of a real bus (a second
//! adapter, or `vcan0` shared with `armgate-sim --can socketcan:vcan0`).
//!
//! The drives are the in-process simulation's own: a [`VirtualBus`] of [`SimWhistle`]s built
//! from the robot file as `--can sim` builds it (interpreter and PDO schedules, faults). The
//! interface stands where that bus has the controller: a frame read from the socket is queued
//! on the virtual bus as the controller's, at the wall-clock time it was read, and every frame
//! the drives put on the virtual bus is written to the socket. The virtual bus keeps the robot
//! file's bit rate and arbitration: the drives receive the controller's frames no closer
//! together than on a real bus of that rate (an emulated bus, QEMU's, delivers a whole burst at
//! once, and a drive's interpreter takes two commands at a time), and their answers come a
//! frame's time later than the interface delivered the request.
//!
//! Faults are injected on standard input, one line each (for tests and for trying what the
//! controller does): `emcy NODE` (the drive sends an emergency, "message lost": `ER32`),
//! `heartbeat-lost NODE` (the drive reports the controller's heartbeat lost: `ER36`),
//! `silent NODE` (the drive sends nothing from now on).
//!
//! [`SimWhistle`]: armgate_core::sim::SimWhistle

use std::collections::VecDeque;
use std::io::BufRead;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver};
use std::time::{Duration, Instant, SystemTime};

use armgate_core::config::ValidRobot;
use armgate_core::drives::{BusState, CanBus, DriveEmergency};
use armgate_core::kinematics::Joints;
use armgate_core::sim::{Stalled, VirtualBus};
use armgate_protocol::can::CanFrame;

use armgate_socketcan::{self as socketcan, Pacer, SocketCan};

/// How long the loop waits for a frame: it runs the drives at least this often, so their
/// answers leave within this of when the drive sent them (the controller reads them at its next
/// tick, a period later); a frame read wakes it at once and is put on the bus at its arrival
/// whenever it is read. Longer waits cost an emulated machine less (each wake-up is work).
const WAIT: Duration = Duration::from_millis(1);

/// A turn of the loop later than this after the previous one is counted (s): the drives'
/// answers are held up, and with 5 ms a PT stream underflows (docs/drives.md).
const LATE: f64 = 2e-3;

/// Frames read from the interface and waiting for room on the virtual bus, at most: a few
/// cycles of the busiest schedule (28 frames), for a process that was not scheduled for a while.
const BACKLOG: usize = 256;

/// A fault to inject, from a line of standard input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fault {
    /// The drive sends an emergency ("message lost").
    Emergency(u8),
    /// The drive reports the controller's heartbeat lost.
    HeartbeatLost(u8),
    /// The drive sends nothing from now on.
    Silent(u8),
}

impl Fault {
    /// Parses `emcy NODE`, `heartbeat-lost NODE` or `silent NODE`.
    pub fn parse(line: &str) -> Result<Self, String> {
        let mut words = line.split_whitespace();
        let (Some(kind), Some(node), None) = (words.next(), words.next(), words.next()) else {
            return Err(format!("`{line}`: expected KIND NODE"));
        };
        let node: u8 = node
            .parse()
            .map_err(|_| format!("`{line}`: {node} is not a node id"))?;
        match kind {
            "emcy" => Ok(Self::Emergency(node)),
            "heartbeat-lost" => Ok(Self::HeartbeatLost(node)),
            "silent" => Ok(Self::Silent(node)),
            _ => Err(format!(
                "`{line}`: {kind} is not one of emcy, heartbeat-lost, silent"
            )),
        }
    }

    fn node(self) -> u8 {
        match self {
            Self::Emergency(node) | Self::HeartbeatLost(node) | Self::Silent(node) => node,
        }
    }

    /// Applies the fault to its drive on `bus`; false if no drive has that node id.
    fn apply(self, bus: &mut VirtualBus) -> bool {
        let Some(drive) = bus.drive_mut(self.node()) else {
            return false;
        };
        match self {
            Self::Emergency(_) => drive.inject(DriveEmergency::MessageLost),
            Self::HeartbeatLost(_) => drive.inject(DriveEmergency::HeartbeatLost),
            Self::Silent(_) => drive.faults.silent = true,
        }
        true
    }
}

/// What crossed between the interface and the simulated bus.
#[derive(Clone, Copy, Debug, Default)]
struct Counters {
    /// Frames read from the interface.
    received: u64,
    /// Frames the drives sent, written to the interface.
    sent: u64,
    /// Frames read that found the backlog full ([`BACKLOG`]).
    dropped_in: u64,
    /// Frames of the drives the interface refused (queue full, bus-off).
    dropped_out: u64,
    /// Frames read more than [`LATE`] after they arrived, and the longest wait (s): how far
    /// behind the loop was, made up by putting each frame at its arrival.
    read_late: u64,
    worst_wait: f64,
}

/// The simulated Whistles behind an interface: the virtual bus, the frames read and waiting
/// for room on it (with their arrival, s), and what crossed.
pub struct Whistles {
    bus: VirtualBus,
    backlog: VecDeque<(CanFrame, f64)>,
    counters: Counters,
}

impl Whistles {
    /// The drives of `config` with their encoders at `start`, at time 0.
    pub fn new(config: &ValidRobot, start: &Joints) -> Self {
        Self {
            bus: VirtualBus::for_robot_at(config, start),
            backlog: VecDeque::with_capacity(BACKLOG),
            counters: Counters::default(),
        }
    }

    /// Runs the drives up to `now` (s) with the frames `received` since the last step, each
    /// queued on the virtual bus at its arrival (s, at most `now`), and writes the drives'
    /// frames to `iface`.
    ///
    /// A frame goes on the virtual bus at the time it arrived, not when the loop got to read
    /// it: a drive of the bus has it then. Queued when read, a point that arrived while this
    /// process was not scheduled (tens of milliseconds in an emulated machine) reached the
    /// drives after they had run past the time they needed it, and their PT buffers underflowed
    /// (`ER33`) although the controller had sent every point in time.
    pub fn step(
        &mut self,
        now: f64,
        received: impl IntoIterator<Item = (CanFrame, f64)>,
        iface: &mut impl CanBus,
    ) -> Result<(), Stalled> {
        for (frame, arrived) in received {
            self.counters.received += 1;
            let wait = now - arrived;
            self.counters.worst_wait = self.counters.worst_wait.max(wait);
            if wait > LATE {
                self.counters.read_late += 1;
            }
            if self.backlog.len() < BACKLOG {
                self.backlog.push_back((frame, arrived));
            } else {
                self.counters.dropped_in += 1;
            }
        }
        // In order, each at its arrival, as many as the virtual bus's controller queue takes;
        // the rest wait. The drives' answers meanwhile are written as they come (the virtual
        // bus holds a few cycles of them).
        while let Some(&(frame, arrived)) = self.backlog.front() {
            self.bus.advance(arrived.min(now))?;
            self.write(iface);
            if self.bus.try_transmit(&frame).is_err() {
                break;
            }
            self.backlog.pop_front();
        }
        self.bus.advance(now)?;
        self.write(iface);
        // A bus-off is the kernel's to restart (`restart-ms`); the drives have no client to
        // wait for, so they try again at once.
        if iface.state() == BusState::BusOff {
            iface.recover();
        }
        Ok(())
    }

    /// Writes the frames the drives put on the virtual bus to `iface`.
    fn write(&mut self, iface: &mut impl CanBus) {
        while let Some(frame) = self.bus.try_receive() {
            match iface.try_transmit(&frame) {
                Ok(()) => self.counters.sent += 1,
                Err(_) => self.counters.dropped_out += 1,
            }
        }
    }
}

/// The frames `socket` holds, each with its [`arrival`] on the loop's clock (s), the first
/// not before `after` (the previous frame's).
fn read(socket: &mut SocketCan, now: f64, after: f64) -> Vec<(CanFrame, f64)> {
    let wall = SystemTime::now();
    let mut frames = Vec::new();
    let mut previous = after;
    while let Some((frame, stamp)) = socket.try_receive_stamped() {
        previous = arrival(now, wall, stamp, previous);
        frames.push((frame, previous));
    }
    frames
}

/// When a frame arrived on the loop's clock (s): `now` (read from it at `wall` on the wall
/// clock) less the age of the kernel's timestamp `stamp`; `now` without a timestamp or with one
/// ahead of `wall`; never before `previous` (frames arrive in order) nor after `now`.
fn arrival(now: f64, wall: SystemTime, stamp: Option<SystemTime>, previous: f64) -> f64 {
    let age = stamp
        .and_then(|s| wall.duration_since(s).ok())
        .map_or(0.0, |age| age.as_secs_f64());
    (now - age).max(previous).min(now)
}

/// Serves the simulated Whistles of `config`, with their encoders at `start`, on interface
/// `iface` (writes held to the robot file's bit rate if `paced`) until `running` turns false
/// or `duration` (s) has passed.
pub fn serve(
    config: &ValidRobot,
    start: &Joints,
    (iface, paced): (&str, bool),
    duration: Option<f64>,
    running: &Arc<AtomicBool>,
) -> Result<(), String> {
    let pacer = paced.then(|| Pacer::new(config.drives.can_bitrate));
    let mut socket = SocketCan::open(iface, pacer).map_err(|e| socketcan::explain(iface, &e))?;
    let mut whistles = Whistles::new(config, start);
    let nodes: Vec<String> = whistles
        .bus
        .drives()
        .map(|d| d.node().get().to_string())
        .collect();
    let faults = read_faults();
    eprintln!(
        "armgate-sim: simulated Whistles of {} (nodes {}) on socketcan:{iface}; faults on stdin: emcy|heartbeat-lost|silent NODE",
        config.name,
        nodes.join(", "),
    );
    let epoch = Instant::now();
    let (mut last, mut worst_gap, mut late) = (0.0f64, 0.0f64, 0u64);
    let mut arrived = 0.0f64;
    while running.load(Ordering::SeqCst) {
        socket
            .wait_readable(WAIT)
            .map_err(|e| format!("socketcan:{iface}: {e}"))?;
        let now = epoch.elapsed().as_secs_f64();
        worst_gap = worst_gap.max(now - last);
        if now - last > LATE {
            late += 1;
        }
        last = now;
        if duration.is_some_and(|d| now >= d) {
            break;
        }
        for fault in faults.try_iter() {
            if !fault.apply(&mut whistles.bus) {
                eprintln!("armgate-sim: no drive with node id {}", fault.node());
            }
        }
        let frames = read(&mut socket, now, arrived);
        arrived = frames.last().map_or(arrived, |&(_, at)| at);
        whistles
            .step(now, frames, &mut socket)
            .map_err(|_| "the simulated drives stalled".to_owned())?;
    }
    let (counters, c) = (whistles.counters, socket.counters());
    let stats = whistles.bus.stats();
    eprintln!(
        "armgate-sim: Whistles stopped; {} frames received, {} sent, {} dropped inbound (backlog full), {} refused by the interface, {} answers lost (virtual bus inbox full); SocketCAN: {} bus-offs, {} frames refused by a full transmit queue; {late} turns of the loop came over {:.0} ms late, the worst {:.1} ms; {} frames read over {:.0} ms after they arrived, the worst {:.1} ms (each put on the bus at its arrival); drives: {} PT underflows, {} commands lost (interpreter busy)",
        counters.received,
        counters.sent,
        counters.dropped_in,
        counters.dropped_out,
        stats.inbox_overruns,
        c.bus_offs,
        c.queue_full,
        LATE * 1e3,
        worst_gap * 1e3,
        counters.read_late,
        LATE * 1e3,
        counters.worst_wait * 1e3,
        whistles
            .bus
            .drives()
            .map(|d| d.stats().underflows)
            .sum::<u32>(),
        whistles
            .bus
            .drives()
            .map(|d| d.stats().commands_lost)
            .sum::<u32>(),
    );
    Ok(())
}

/// Faults typed on standard input, read on a thread of their own (a line that is not a fault
/// is reported and ignored; the end of input ends nothing).
fn read_faults() -> Receiver<Fault> {
    let (sender, receiver) = mpsc::channel();
    std::thread::spawn(move || {
        for line in std::io::stdin().lock().lines() {
            let Ok(line) = line else { return };
            if line.trim().is_empty() {
                continue;
            }
            match Fault::parse(&line) {
                Ok(fault) => {
                    eprintln!("armgate-sim: injecting {fault:?}");
                    if sender.send(fault).is_err() {
                        return;
                    }
                }
                Err(e) => eprintln!("armgate-sim: {e}"),
            }
        }
    });
    receiver
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use std::cell::{Cell, RefCell};
    use std::rc::Rc;

    use armgate_core::command::Drives;
    use armgate_core::cycle::{CanDrives, DriveSide};
    use armgate_core::drives::{DriveSettings, TxError};
    use armgate_protocol::client::{DriveStatus, Text};

    use super::*;

    /// One end of a bus without timing between two processes, as QEMU's: what one end sends,
    /// the other receives at once, in order, stamped with the time on `clock` it was sent.
    struct End {
        out: Rc<RefCell<VecDeque<(CanFrame, f64)>>>,
        inbox: Rc<RefCell<VecDeque<(CanFrame, f64)>>>,
        clock: Rc<Cell<f64>>,
    }

    impl End {
        /// Every frame waiting, with when it was sent.
        fn stamped(&self) -> Vec<(CanFrame, f64)> {
            self.inbox.borrow_mut().drain(..).collect()
        }
    }

    impl CanBus for End {
        fn try_transmit(&mut self, frame: &CanFrame) -> Result<(), TxError> {
            self.out.borrow_mut().push_back((*frame, self.clock.get()));
            Ok(())
        }

        fn try_receive(&mut self) -> Option<CanFrame> {
            self.inbox.borrow_mut().pop_front().map(|(frame, _)| frame)
        }

        fn state(&self) -> BusState {
            BusState::from_bus_off(false)
        }
    }

    fn wire(clock: &Rc<Cell<f64>>) -> (End, End) {
        let (a, b) = (Rc::default(), Rc::default());
        (
            End {
                out: Rc::clone(&a),
                inbox: Rc::clone(&b),
                clock: Rc::clone(clock),
            },
            End {
                out: b,
                inbox: a,
                clock: Rc::clone(clock),
            },
        )
    }

    fn ranger() -> ValidRobot {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../robots/ranger-mk1.toml");
        armgate_core::config::load_file(std::path::Path::new(path)).unwrap()
    }

    #[test]
    fn the_drive_manager_starts_and_holds_the_whistles_across_an_untimed_bus() {
        assert_eq!(holds(&ranger(), 5e-4, true), None);
        // The PDO schedule at its fastest period for ranger-mk1 (12 samples, 4.32 ms).
        let pdo = ranger()
            .edit(|config| {
                config.drives.streaming = armgate_core::config::Streaming::Pdo;
                config.control_period = 12.0 * armgate_core::config::SAMPLE_TIME;
            })
            .unwrap();
        assert_eq!(holds(&pdo, 5e-4, true), None);
    }

    #[test]
    fn frames_read_late_are_put_on_the_bus_at_their_arrival_and_the_stream_holds() {
        // The Whistles' loop runs only every 25 ms, longer than ranger-mk1's period (19.44 ms):
        // each PT point waits in the socket past the segment boundary that needs it.
        assert_eq!(holds(&ranger(), 25e-3, true), None);
        // Put on the bus when read instead, the drives see points and queries bunched up to
        // 25 ms late, and the stream breaks (ER33 underflow, or ER34: the read index answered
        // late shows the drive behind its points).
        let fault = holds(&ranger(), 25e-3, false).unwrap();
        assert!(
            ["ER33", "ER34"]
                .iter()
                .any(|code| fault.as_str().starts_with(code)),
            "{fault}"
        );
    }

    /// The drive manager of `config` and its Whistles across [`wire`], the Whistles' loop
    /// turning every `every` s, each frame put on their bus at its sending (`stamped`) or when
    /// the loop reads it: the drive manager's fault after 3 s (started, running), if any.
    fn holds(config: &ValidRobot, every: f64, stamped: bool) -> Option<Text> {
        let config = config.clone();
        let start = config.home();
        let clock = Rc::new(Cell::new(0.0));
        let (controller, mut iface) = wire(&clock);
        let mut drives =
            CanDrives::started(&config, &DriveSettings::default(), controller).unwrap();
        let mut whistles = Whistles::new(&config, &start);
        let period = config.control_period;
        // The controller's tick every period and the Whistles' loop every `every`, for 3 s,
        // on a 0.5 ms grid.
        let (mut next_tick, mut next_turn) = (0.0, 0.0);
        for k in 0..6000 {
            let now = f64::from(k) * 5e-4;
            clock.set(now);
            if now >= next_turn {
                let frames = iface
                    .stamped()
                    .into_iter()
                    .map(|(frame, sent)| (frame, if stamped { sent } else { now }));
                whistles.step(now, frames, &mut iface).unwrap();
                next_turn += every;
            }
            if now >= next_tick {
                drives.receive(now);
                drives.transmit(now, period, None);
                next_tick += period;
            }
        }
        if drives.fault().is_none() {
            assert_eq!(drives.status(), DriveStatus::Running);
        }
        drives.fault()
    }

    #[test]
    fn a_frame_arrives_at_its_kernel_timestamp_on_the_loop_clock_in_order_never_ahead() {
        let wall = SystemTime::UNIX_EPOCH + Duration::from_secs(1_000);
        let ago = |ms| Some(wall - Duration::from_millis(ms));
        // Read at 10 s on the loop's clock: received 30 ms before, at 9.97 s.
        assert!((arrival(10.0, wall, ago(30), 0.0) - 9.97).abs() < 1e-9);
        // Not before the previous frame (the wall clock stepped back, or out of order).
        assert!((arrival(10.0, wall, ago(30), 9.99) - 9.99).abs() < 1e-12);
        // No timestamp, or one from the future: when read.
        assert!((arrival(10.0, wall, None, 0.0) - 10.0).abs() < 1e-12);
        let ahead = Some(wall + Duration::from_millis(5));
        assert!((arrival(10.0, wall, ahead, 0.0) - 10.0).abs() < 1e-12);
        // Received before the loop's clock began (0 s): at its start.
        assert!(arrival(0.01, wall, ago(50), 0.0).abs() < 1e-12);
    }

    #[test]
    fn fault_lines_parse_and_bad_ones_say_why() {
        assert_eq!(Fault::parse("emcy 3"), Ok(Fault::Emergency(3)));
        assert_eq!(
            Fault::parse(" heartbeat-lost 1 "),
            Ok(Fault::HeartbeatLost(1))
        );
        assert_eq!(Fault::parse("silent 6"), Ok(Fault::Silent(6)));
        assert!(Fault::parse("silent").unwrap_err().contains("KIND NODE"));
        assert!(
            Fault::parse("emcy x")
                .unwrap_err()
                .contains("not a node id")
        );
        assert!(Fault::parse("melt 2").unwrap_err().contains("not one of"));
        assert!(Fault::parse("emcy 1 2").is_err());
    }

    #[test]
    fn an_injected_emergency_reaches_the_interface_side_and_silent_drives_send_nothing() {
        let mut bus = VirtualBus::for_robot(&ranger());
        bus.advance(0.5).unwrap();
        while bus.try_receive().is_some() {}
        // ranger-mk1's drives are nodes 101 to 106.
        assert!(Fault::Emergency(102).apply(&mut bus));
        assert!(!Fault::Emergency(2).apply(&mut bus));
        bus.advance(0.51).unwrap();
        let frames: Vec<CanFrame> = std::iter::from_fn(|| bus.try_receive()).collect();
        // EMCY of node 102: 0x80 + 102.
        assert!(frames.iter().any(|f| f.id() == 0x80 + 102), "{frames:?}");
        assert!(Fault::Silent(102).apply(&mut bus));
        assert!(Fault::Emergency(102).apply(&mut bus));
        bus.advance(0.6).unwrap();
        let frames: Vec<CanFrame> = std::iter::from_fn(|| bus.try_receive()).collect();
        assert!(frames.iter().all(|f| f.id() & 0x7f != 102), "{frames:?}");
    }
}
