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
use std::time::{Duration, Instant};

use armgate_core::config::ValidRobot;
use armgate_core::drives::{BusState, CanBus, DriveEmergency};
use armgate_core::kinematics::Joints;
use armgate_core::sim::{Stalled, VirtualBus};
use armgate_protocol::can::CanFrame;

use crate::socketcan::{self, Pacer, SocketCan};

/// How long the loop waits for a frame: it runs the drives at least this often, so their
/// answers (250 µs after a command) leave about on time, and a frame read wakes it at once.
const WAIT: Duration = Duration::from_micros(200);

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
}

/// The simulated Whistles behind an interface: the virtual bus, the frames read and waiting
/// for room on it, and what crossed.
pub struct Whistles {
    bus: VirtualBus,
    backlog: VecDeque<CanFrame>,
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

    /// Runs the drives up to `now` (s), then queues the frames `iface` has for them and writes
    /// theirs to it.
    pub fn step(&mut self, now: f64, iface: &mut impl CanBus) -> Result<(), Stalled> {
        self.bus.advance(now)?;
        while let Some(frame) = iface.try_receive() {
            self.counters.received += 1;
            if self.backlog.len() < BACKLOG {
                self.backlog.push_back(frame);
            } else {
                self.counters.dropped_in += 1;
            }
        }
        // In order, as many as the virtual bus's controller queue takes; the rest wait.
        while let Some(frame) = self.backlog.front() {
            if self.bus.try_transmit(frame).is_err() {
                break;
            }
            self.backlog.pop_front();
        }
        while let Some(frame) = self.bus.try_receive() {
            match iface.try_transmit(&frame) {
                Ok(()) => self.counters.sent += 1,
                Err(_) => self.counters.dropped_out += 1,
            }
        }
        // A bus-off is the kernel's to restart (`restart-ms`); the drives have no client to
        // wait for, so they try again at once.
        if iface.state() == BusState::BusOff {
            iface.recover();
        }
        Ok(())
    }
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
        whistles
            .step(now, &mut socket)
            .map_err(|_| "the simulated drives stalled".to_owned())?;
    }
    let (counters, c) = (whistles.counters, socket.counters());
    eprintln!(
        "armgate-sim: Whistles stopped; {} frames received, {} sent, {} dropped inbound (backlog full), {} refused by the interface; SocketCAN: {} bus-offs, {} frames refused by a full transmit queue; {late} turns of the loop came over {:.0} ms late, the worst {:.1} ms",
        counters.received,
        counters.sent,
        counters.dropped_in,
        counters.dropped_out,
        c.bus_offs,
        c.queue_full,
        LATE * 1e3,
        worst_gap * 1e3,
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
    use std::cell::RefCell;
    use std::rc::Rc;

    use armgate_core::command::Drives;
    use armgate_core::cycle::{CanDrives, DriveSide};
    use armgate_core::drives::{DriveSettings, TxError};
    use armgate_protocol::client::DriveStatus;

    use super::*;

    /// One end of a bus without timing between two processes, as QEMU's: what one end sends,
    /// the other receives at once, in order.
    struct End {
        out: Rc<RefCell<VecDeque<CanFrame>>>,
        inbox: Rc<RefCell<VecDeque<CanFrame>>>,
    }

    impl CanBus for End {
        fn try_transmit(&mut self, frame: &CanFrame) -> Result<(), TxError> {
            self.out.borrow_mut().push_back(*frame);
            Ok(())
        }

        fn try_receive(&mut self) -> Option<CanFrame> {
            self.inbox.borrow_mut().pop_front()
        }

        fn state(&self) -> BusState {
            BusState::from_bus_off(false)
        }
    }

    fn wire() -> (End, End) {
        let (a, b) = (Rc::default(), Rc::default());
        (
            End {
                out: Rc::clone(&a),
                inbox: Rc::clone(&b),
            },
            End { out: b, inbox: a },
        )
    }

    fn ranger() -> ValidRobot {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../robots/ranger-mk1.toml");
        armgate_core::config::load_file(std::path::Path::new(path)).unwrap()
    }

    #[test]
    fn the_drive_manager_starts_and_holds_the_whistles_across_an_untimed_bus() {
        holds(&ranger());
        // The PDO schedule at its fastest period for ranger-mk1 (12 samples, 4.32 ms).
        let pdo = ranger()
            .edit(|config| {
                config.drives.streaming = armgate_core::config::Streaming::Pdo;
                config.control_period = 12.0 * armgate_core::config::SAMPLE_TIME;
            })
            .unwrap();
        holds(&pdo);
    }

    /// The drive manager of `config` and its Whistles across [`wire`]: started, running, no
    /// fault after 3 s.
    fn holds(config: &ValidRobot) {
        let config = config.clone();
        let start = config.home();
        let (controller, mut iface) = wire();
        let mut drives =
            CanDrives::started(&config, &DriveSettings::default(), controller).unwrap();
        let mut whistles = Whistles::new(&config, &start);
        let period = config.control_period;
        // The Whistles' loop every 0.5 ms, the controller's tick every period, for 3 s.
        let mut next_tick = 0.0;
        for k in 0..6000 {
            let now = f64::from(k) * 5e-4;
            whistles.step(now, &mut iface).unwrap();
            if now >= next_tick {
                drives.receive(now);
                drives.transmit(now, period, None);
                next_tick += period;
            }
        }
        assert_eq!(drives.fault(), None, "{:?}", whistles.counters);
        assert_eq!(drives.status(), DriveStatus::Running);
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
