//! Fuzz target: client datagrams and CAN frames through the core's control cycle — the
//! protocol parser, the command handling, the drive manager and the CAN frame parsing — with
//! control ticks in between so that the motions they start actually run.
//!
//! Input format (every byte string is valid): a sequence of chunks, each one header byte `h`:
//!
//! * bits 0–1: the control ticks run after the chunk: 0, 1, 8 or 64;
//! * bit 2 clear: a **datagram** of `h >> 3` bytes (0..=31; fewer if the input ends first),
//!   queued for the cycle (at most 8 are answered per tick, one of them planning, in order);
//! * bit 2 set, bits 3–6 below 15: a **CAN frame** the drive manager receives as if from the
//!   bus: bits 3–6 are the data length (capped at 8), then two bytes of identifier
//!   (little-endian, 11 bits), then the data;
//! * bit 2 set, bits 3–6 = 15: a **signed datagram**: a control byte `c`, then the 31-byte
//!   message (zero-filled if the input ends). It is signed with the fuzz key on link `c & 7`
//!   (0 is the controller's own: refused) at the link's last timestamp + `(c >> 3 & 7)` − 2
//!   (so 0 or less repeat or go back: refused as replays); `c` bit 6 flips a tag bit (forged),
//!   bit 7 cuts the block to 40 bytes (truncated).
//!
//! Every input starts from the same state: the [`Cycle`] of `robots/ranger-mk1.toml` with the
//! drive manager on a virtual bus of simulated Whistles at their home angles, the drives
//! started and streaming, a signing key set and unsigned datagrams allowed to do everything
//! (so the unsigned chunks exercise the handler as they did without a key). At most [`MAX_TICKS`] ticks run per input; at the end, ticks run
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
//! A signed datagram is answered if and only if the target's own model of the rules (a client
//! link, the right tag, a whole block, a timestamp newer than the link's last one) says so,
//! and then its answer and the notices after it are signed: the key's tag on the controller's
//! link, a timestamp not older than the request's. (The answer itself is checked as above.)
//!
//! and for every tick: every joint command is finite and within the joint limits, its
//! acceleration (against the two commands before it) within `max_acceleration` (+1e-9
//! relative) — a following-error stop (cause 9, `ER43`, which an injected position report can
//! cause) included —, no link of the arm at the command comes into contact with the base
//! column, the bounds (the tool's capsule) or another link (`BodyOracle`, issue 35: the arm
//! starts clear at home), and every unsolicited notice is one of `WN12`, `WN13`, `ER21`,
//! `WN22`, `WN27`, `ER41`, `ER43` or a drive fault `ER3x`.
#![no_main]

use std::collections::VecDeque;
use std::sync::OnceLock;

use armgate_core::config::{ValidRobot, load_file};
use armgate_core::cycle::{
    CanDrives, Cycle, Datagram, Dropped, Link, Outgoing, Signing, UnsignedAccess,
};
use armgate_core::drives::{BusState, CanBus, DriveSettings, TxError};
use armgate_core::kinematics::Joints;
use armgate_core::sim::{BodyOracle, VirtualBus};
use armgate_protocol::can::CanFrame;
use armgate_protocol::client::signed::{
    CONTROLLER_LINK, SIGNED_LEN, Signature, Signed, SigningKey,
};
use armgate_protocol::client::{MESSAGE_LEN, Notice, Request};
use libfuzzer_sys::fuzz_target;

mod checks;
use checks::{check_notice, check_parsers, check_reply};

/// Ticks run after a chunk, by header bits 0–1.
const TICKS: [u32; 4] = [0, 1, 8, 64];
/// Ticks per input at most (before the final ones that answer what waits).
const MAX_TICKS: u32 = 256;
/// Ticks the drives may take to start.
const START_TICKS: u32 = 200;

/// The fuzz target's signing key.
const KEY: [u8; 32] = [0x42; 32];
/// The CAN length field that marks a signed datagram instead.
const SIGNED_CHUNK: u8 = 15;

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
struct Client {
    /// The last two joint commands (cleared when none is sent).
    commands: Vec<Joints>,
    waiting: VecDeque<Datagram<()>>,
    /// Requests sent and not yet answered, with what the parsers made of them and, for a
    /// signed one, its timestamp (its answer must be signed and not older).
    unanswered: VecDeque<(Vec<u8>, Result<Request, Notice>, Option<u64>)>,
    key: SigningKey,
    /// Per link id, the last timestamp served (the model of the controller's replay table).
    last: [Option<u64>; 8],
    /// Every command's pose against the column, the bounds and the other links.
    body: BodyOracle,
}

impl Default for Client {
    fn default() -> Self {
        Self {
            commands: Vec::new(),
            waiting: VecDeque::new(),
            unanswered: VecDeque::new(),
            key: SigningKey::new(&KEY),
            last: [None; 8],
            body: body_at_home().clone(),
        }
    }
}

impl Client {
    /// Queues the signed datagram of a chunk; it is expected to be answered only if the rules
    /// let it through.
    fn push_signed(&mut self, control: u8, message: &[u8]) {
        let mut bytes = [0u8; MESSAGE_LEN];
        bytes.iter_mut().zip(message).for_each(|(b, m)| *b = *m);
        let link = control & 7;
        let slot = usize::from(link);
        let base = self.last[slot].unwrap_or(1_000);
        let timestamp = (base + u64::from(control >> 3 & 7)).saturating_sub(2);
        let mut signed = Signature { link, timestamp }.emit(&bytes, &self.key);
        let forged = control & 0x40 != 0;
        if forged {
            signed[SIGNED_LEN - 1] ^= 0x10;
        }
        let len = if control & 0x80 != 0 { 40 } else { SIGNED_LEN };
        self.waiting.push_back(Datagram::new(&signed[..len], ()));
        let fresh = self.last[slot].is_none_or(|last| timestamp > last);
        // A validly signed stop is served even when not fresh (and moves nothing on).
        let stop = matches!(bytes[..2], [b'S', b'T'] | [b'j', b'R']);
        if link == CONTROLLER_LINK || forged || len < SIGNED_LEN || !(fresh || stop) {
            return;
        }
        if fresh {
            self.last[slot] = Some(timestamp);
        }
        let expected = check_parsers(&bytes);
        self.unanswered
            .push_back((bytes.to_vec(), expected, Some(timestamp)));
    }

    /// The 31-byte message of an answer; a signed one is verified (after `not_before`).
    fn open(&self, payload: &[u8], not_before: Option<u64>) -> [u8; MESSAGE_LEN] {
        let message = match not_before {
            None => payload,
            Some(at) => {
                let block = Signed::new_checked(payload).expect("a signed answer");
                let signature = Signature::parse(&block, &self.key).expect("the key's tag");
                assert_eq!(signature.link, CONTROLLER_LINK);
                assert!(
                    signature.timestamp >= at,
                    "an answer older than its request"
                );
                &payload[..MESSAGE_LEN]
            }
        };
        message.try_into().expect("31 bytes")
    }
}

impl Link<()> for Client {
    fn receive(&mut self) -> Option<Datagram<()>> {
        self.waiting.pop_front()
    }

    fn send(&mut self, datagram: &Datagram<()>, kind: Outgoing) -> Result<(), Dropped> {
        match kind {
            Outgoing::Reply => {
                let (request, expected, signed) =
                    self.unanswered.pop_front().expect("a reply to nothing");
                let bytes = self.open(datagram.payload(), signed);
                check_reply(&request, expected, &bytes);
            }
            // Signed for a signed recipient (the holder, or the last sender, by link id),
            // unsigned for an unsigned one: whichever it is, a signed one must be genuine.
            Outgoing::Notice => {
                let signed = (datagram.payload().len() == SIGNED_LEN).then_some(0);
                check_notice(&self.open(datagram.payload(), signed));
            }
        }
        Ok(())
    }
}

/// The robot of every run.
fn robot() -> &'static ValidRobot {
    static ROBOT_CONFIG: OnceLock<ValidRobot> = OnceLock::new();
    ROBOT_CONFIG.get_or_init(|| load_file(ROBOT).unwrap_or_else(|e| panic!("{ROBOT}: {e}")))
}

/// The arm's body from home, where every input starts (the robot file's check: clear).
fn body_at_home() -> &'static BodyOracle {
    static BODY: OnceLock<BodyOracle> = OnceLock::new();
    BODY.get_or_init(|| BodyOracle::new(robot(), &robot().home()))
}

fn start() -> &'static FuzzCycle {
    static START: OnceLock<FuzzCycle> = OnceLock::new();
    START.get_or_init(|| {
        let config = robot();
        let bus = FuzzBus {
            bus: VirtualBus::for_robot(config),
            injected: VecDeque::new(),
        };
        let drives = CanDrives::started(config, &DriveSettings::default(), bus).expect("drives");
        let signing = Signing {
            key: Some(SigningKey::new(&KEY)),
            unsigned: UnsignedAccess::All,
        };
        let mut cycle = Cycle::new(config, drives).with_signing(signing);
        let mut client = Client::default();
        for _ in 0..START_TICKS {
            if cycle.drives().manager().is_operational() {
                break;
            }
            tick(&mut cycle, &mut client);
        }
        assert!(
            cycle.drives().manager().is_operational(),
            "the drives did not start"
        );
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
        assert!(
            cmd.is_finite(),
            "t {}: non-finite command {cmd:?}",
            outcome.time
        );
        assert!(
            cycle.handler().controller().chain().within_limits(cmd),
            "t {}: command beyond the joint limits {cmd:?}",
            outcome.time
        );
        if let [a, b] = client.commands[..] {
            let config = robot();
            let dt = config.control_period;
            for (j, joint) in config.joints.iter().enumerate() {
                let acc = (cmd[j] - 2.0 * b[j] + a[j]) / (dt * dt);
                assert!(
                    acc.abs() <= joint.max_acceleration * (1.0 + 1e-9),
                    "t {}: joint {j} accelerates at {acc}",
                    outcome.time
                );
            }
        }
        if let Err(entry) = client.body.check(cmd) {
            panic!(
                "t {}: {} entered (gap {} m) at {cmd:?}",
                outcome.time, entry.hit, entry.gap
            );
        }
        client.commands.push(*cmd);
        if client.commands.len() > 2 {
            client.commands.remove(0);
        }
    } else {
        client.commands.clear();
    }
}

fuzz_target!(|data: &[u8]| {
    let mut cycle = start().clone();
    let mut client = Client::default();
    let mut ticks = 0u32;
    let mut rest = data;
    while let Some((&header, tail)) = rest.split_first() {
        rest = tail;
        if header & 0b100 == 0 {
            let len = usize::from(header >> 3);
            let (datagram, tail) = rest.split_at(len.min(rest.len()));
            rest = tail;
            let expected = check_parsers(datagram);
            client
                .unanswered
                .push_back((datagram.to_vec(), expected, None));
            client.waiting.push_back(Datagram::new(datagram, ()));
        } else if (header >> 3) & 0x0F == SIGNED_CHUNK {
            let (chunk, tail) = rest.split_at((1 + MESSAGE_LEN).min(rest.len()));
            rest = tail;
            if let Some((&control, message)) = chunk.split_first() {
                client.push_signed(control, message);
            }
        } else {
            let len = usize::from((header >> 3) & 0x0F).min(8);
            let (frame, tail) = rest.split_at((2 + len).min(rest.len()));
            rest = tail;
            if let [lo, hi, data @ ..] = frame {
                let id = u16::from_le_bytes([*lo, *hi]) & 0x7FF;
                if let Ok(frame) = CanFrame::new(id, data) {
                    cycle.drives_mut().bus_mut().injected.push_back(frame);
                }
            }
        }
        for _ in 0..TICKS[usize::from(header & 0b11)] {
            if ticks >= MAX_TICKS {
                break;
            }
            ticks += 1;
            tick(&mut cycle, &mut client);
        }
    }
    // Answer what still waits: the cycle handles at least one request a tick (more wait for
    // its planning budget), and a planning request's work runs in slices, one a tick (a `KG`'s
    // search, a line's check: `cycle::budget`), so each request left is given a few hundred
    // ticks; the loop ends as soon as nothing waits.
    const TICKS_PER_REQUEST: usize = 400;
    for _ in 0..(client.waiting.len() + client.unanswered.len() + 1) * TICKS_PER_REQUEST {
        if client.waiting.is_empty() && client.unanswered.is_empty() {
            break;
        }
        tick(&mut cycle, &mut client);
    }
    assert!(client.unanswered.is_empty(), "requests left unanswered");
});
