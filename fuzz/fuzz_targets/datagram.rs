//! Fuzz target: client datagrams and CAN frames through the core's control cycle — the
//! protocol parser, the command handling, the drive manager and the CAN frame parsing — with
//! control ticks in between so that the motions they start actually run.
//!
//! Input format (every byte string is valid): a sequence of chunks, each one header byte `h`:
//!
//! * bits 0–1: the control ticks run after the chunk: 0, 1, 8 or 64;
//! * bit 2 clear: a **datagram** of `h >> 3` bytes (0..=31; fewer if the input ends first),
//!   queued for the cycle (at most 8 are answered per tick, in order);
//! * bit 2 set: a **CAN frame** the drive manager receives as if from the bus: bits 3–6 are the
//!   data length (capped at 8), then two bytes of identifier (little-endian, 11 bits), then
//!   the data.
//!
//! Every input starts from the same state: the [`Cycle`] of `robots/ranger-mk1.toml` with the
//! drive manager on a virtual bus of simulated Whistles at their home angles, the drives
//! started and streaming. At most [`MAX_TICKS`] ticks run per input; at the end, ticks run
//! until every datagram is answered.
//!
//! Checked, for every datagram:
//!
//! * `Message::new_checked`, `Request::parse`, `Reply::parse` and `Text::parse` on the raw bytes
//!   do not panic; a parsed request re-encodes to the same bytes.
//! * its answer is 31 bytes that are either a [`Reply`] to the request's own command (reply
//!   characters reversed, finite values, index 0 or the request's) or one of the `ER` texts
//!   the protocol defines for that request (exact bytes: NUL-terminated, zero-filled). A
//!   datagram that is not a request gets exactly `ER00`/`ER01`.
//!
//! and for every tick: every joint command is finite and within the joint limits, and every
//! unsolicited notice is one of `WN12`, `ER21`, `WN22`, `WN27` or a drive fault `ER3x`.
#![no_main]

use std::collections::VecDeque;
use std::sync::OnceLock;

use armgate_core::config::{ValidRobot, load_file};
use armgate_core::cycle::{CanDrives, Cycle, Datagram, Dropped, Link, Outgoing};
use armgate_core::drives::{BusState, CanBus, DriveSettings, TxError};
use armgate_core::sim::VirtualBus;
use armgate_protocol::can::CanFrame;
use armgate_protocol::client::{MESSAGE_LEN, Notice, Request};
use libfuzzer_sys::fuzz_target;

mod checks;
use checks::{Chunk, check_notice, check_parsers, check_reply, chunks};

/// Ticks run after a chunk, by header bits 0–1.
const TICKS: [u32; 4] = [0, 1, 8, 64];
/// Ticks per input at most (before the final ones that answer what waits).
const MAX_TICKS: u32 = 256;
/// Ticks the drives may take to start.
const START_TICKS: u32 = 200;

/// The robot file, relative to the fuzz crate.
const ROBOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../robots/ranger-mk1.toml");

/// The virtual bus, plus frames the fuzzer makes the manager receive first.
#[derive(Clone)]
struct FuzzBus {
    bus: VirtualBus,
    injected: VecDeque<CanFrame>,
}

impl CanBus for FuzzBus {
    fn try_transmit(&mut self, frame: &CanFrame) -> Result<(), TxError> {
        self.bus.try_transmit(frame)
    }

    fn try_receive(&mut self) -> Option<CanFrame> {
        self.injected.pop_front().or_else(|| self.bus.try_receive())
    }

    fn state(&self) -> BusState {
        self.bus.state()
    }

    fn advance_to(&mut self, now: f64) -> bool {
        self.bus.advance_to(now)
    }
}

type FuzzCycle = Cycle<CanDrives<FuzzBus>, ()>;

/// The client: datagrams waiting, and the answers checked as they come.
#[derive(Default)]
struct Client {
    waiting: VecDeque<Datagram<()>>,
    /// Requests sent and not yet answered, with what the parsers made of them.
    unanswered: VecDeque<(Vec<u8>, Result<Request, Notice>)>,
}

impl Link<()> for Client {
    fn receive(&mut self) -> Option<Datagram<()>> {
        self.waiting.pop_front()
    }

    fn send(&mut self, datagram: &Datagram<()>, kind: Outgoing) -> Result<(), Dropped> {
        let bytes: [u8; MESSAGE_LEN] = datagram.payload().try_into().expect("31 bytes");
        match kind {
            Outgoing::Reply => {
                let (request, expected) = self.unanswered.pop_front().expect("a reply to nothing");
                check_reply(&request, expected, &bytes);
            }
            Outgoing::Notice => check_notice(&bytes),
        }
        Ok(())
    }
}

fn start() -> &'static FuzzCycle {
    static START: OnceLock<FuzzCycle> = OnceLock::new();
    START.get_or_init(|| {
        let config: ValidRobot = load_file(ROBOT).unwrap_or_else(|e| panic!("{ROBOT}: {e}"));
        let bus = FuzzBus {
            bus: VirtualBus::for_robot(&config),
            injected: VecDeque::new(),
        };
        let drives = CanDrives::started(&config, &DriveSettings::default(), bus).expect("drives");
        let mut cycle = Cycle::new(&config, drives);
        let mut client = Client::default();
        for _ in 0..START_TICKS {
            if cycle.drives().manager().is_operational() {
                break;
            }
            tick(&mut cycle, &mut client);
        }
        assert!(cycle.drives().manager().is_operational(), "the drives did not start");
        cycle
    })
}

/// One tick on time, its command checked.
fn tick(cycle: &mut FuzzCycle, client: &mut Client) {
    let due = cycle.next_due_us();
    let outcome = cycle.tick(due, client);
    if let Ok(out) = &outcome.step
        && let Some(cmd) = &out.command
    {
        assert!(cmd.is_finite(), "t {}: non-finite command {cmd:?}", outcome.time);
        assert!(
            cycle.handler().controller().chain().within_limits(cmd),
            "t {}: command beyond the joint limits {cmd:?}",
            outcome.time
        );
    }
}

fuzz_target!(|data: &[u8]| {
    let mut cycle = start().clone();
    let mut client = Client::default();
    let mut ticks = 0u32;
    for (after, chunk) in chunks(data) {
        match chunk {
            Chunk::Datagram(datagram) => {
                let expected = check_parsers(datagram);
                client.unanswered.push_back((datagram.to_vec(), expected));
                client.waiting.push_back(Datagram::new(datagram, ()));
            }
            Chunk::Frame(frame) => cycle.drives_mut().bus_mut().injected.extend(frame),
        }
        for _ in 0..TICKS[after] {
            if ticks >= MAX_TICKS {
                break;
            }
            ticks += 1;
            tick(&mut cycle, &mut client);
        }
    }
    // Answer what still waits (8 per tick).
    for _ in 0..client.waiting.len().div_ceil(8) + 1 {
        tick(&mut cycle, &mut client);
    }
    assert!(client.unanswered.is_empty(), "requests left unanswered");
});
