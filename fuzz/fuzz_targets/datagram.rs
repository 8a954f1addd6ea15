//! Fuzz target: client datagrams through the protocol parser and the core's command handling,
//! with control ticks in between so that the motions they start actually run.
//!
//! Input format (every byte string is valid): a sequence of chunks, each
//!
//! * one header byte `h`: bits 0–5 are the datagram length (0..=40; 41..=63 mean 31), bits 6–7
//!   the number of control ticks run after the datagram: 0, 1, 8 or 64;
//! * then the datagram, `len` bytes (fewer if the input ends first).
//!
//! Every input starts from the same fresh state: a [`CommandHandler`] for
//! `robots/ranger-mk1.toml`, simulated drives with an ideal arm at the drives' home angles, and
//! one tick already run (so that the handler has a measurement). At most [`MAX_TICKS`] ticks run
//! per input.
//!
//! Checked, for every datagram:
//!
//! * `Message::new_checked`, `Request::parse`, `Reply::parse` and `Text::parse` on the raw bytes
//!   do not panic; a parsed request re-encodes to the same bytes.
//! * `CommandHandler::handle` returns 31 bytes that are either a [`Reply`] to the request's own
//!   command (reply characters reversed, finite values, index 0 or the request's) or one of the
//!   `ER` texts the protocol defines for that request (exact bytes: NUL-terminated, zero-filled).
//!   A datagram that is not a request gets exactly `ER00`/`ER01`.
//!
//! and for every tick: `tick` never fails, every joint command is finite and within the joint
//! limits, and every unsolicited notice is one of `WN12`, `ER21`, `WN22`, `WN27`.
#![no_main]

use std::sync::OnceLock;

use armgate_core::command::{ArmModel, CommandHandler, SimulatedDrives};
use armgate_core::config::{ValidRobot, load_file};
use armgate_core::motion::IdealArm;
use armgate_protocol::client::{
    Command, MESSAGE_LEN, MIN_LEN, Message, Notice, Reply, Request, TEXT_CAPACITY, Text,
};
use libfuzzer_sys::fuzz_target;

/// Ticks run after a datagram, by header bits 6–7.
const TICKS: [u32; 4] = [0, 1, 8, 64];
/// Ticks per input at most (the initial tick excluded), to keep each run short.
const MAX_TICKS: u32 = 512;
/// Longest datagram a header can ask for.
const MAX_DATAGRAM: usize = 40;

/// The robot file, relative to the fuzz crate.
const ROBOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../robots/ranger-mk1.toml");

/// The state every input starts from.
struct Start {
    handler: CommandHandler,
    drives: SimulatedDrives,
    period: f64,
}

fn start() -> &'static Start {
    static START: OnceLock<Start> = OnceLock::new();
    START.get_or_init(|| {
        let config: ValidRobot = load_file(ROBOT).unwrap_or_else(|e| panic!("{ROBOT}: {e}"));
        let home = config.home();
        let mut handler = CommandHandler::new(&config);
        let mut drives = SimulatedDrives::new(ArmModel::Ideal(IdealArm::new(home)));
        let period = config.control_period;
        let out = handler
            .tick(0.0, &drives.measured(), &drives)
            .expect("first tick");
        drives.apply(out.command.as_ref(), period);
        while handler.next_notice().is_some() {}
        Start {
            handler,
            drives,
            period,
        }
    })
}

fuzz_target!(|data: &[u8]| {
    let start = start();
    let mut handler = start.handler.clone();
    let mut drives = start.drives.clone();
    let period = start.period;
    let mut ticks = 0u32;
    let mut rest = data;
    while let Some((&header, tail)) = rest.split_first() {
        let len = match usize::from(header & 0x3F) {
            n if n > MAX_DATAGRAM => MESSAGE_LEN,
            n => n,
        };
        let (datagram, tail) = tail.split_at(len.min(tail.len()));
        rest = tail;

        let expected = check_parsers(datagram);
        let reply = handler.handle(datagram, &mut drives);
        check_reply(datagram, expected, &reply);

        for _ in 0..TICKS[usize::from(header >> 6)] {
            if ticks >= MAX_TICKS {
                break;
            }
            ticks += 1;
            let t = f64::from(ticks) * period;
            let measured = drives.measured();
            let out = handler
                .tick(t, &measured, &drives)
                .unwrap_or_else(|e| panic!("tick {ticks} failed: {e:?}; measured {measured:?}"));
            if let Some(cmd) = &out.command {
                assert!(cmd.is_finite(), "tick {ticks}: non-finite command {cmd:?}");
                assert!(
                    handler.controller().chain().within_limits(cmd),
                    "tick {ticks}: command beyond the joint limits {cmd:?}"
                );
            }
            drives.apply(out.command.as_ref(), period);
            while let Some(text) = handler.next_notice() {
                check_notice(&text);
            }
        }
    }
});

/// The protocol parsers on the raw datagram: no panics, and a request round-trips.
fn check_parsers(datagram: &[u8]) -> Result<Request, Notice> {
    let message = match Message::new_checked(datagram) {
        Ok(message) => message,
        Err(e) => {
            assert!(datagram.len() < MIN_LEN);
            return Err(Notice::from(e));
        }
    };
    assert!(datagram.len() >= MIN_LEN);
    // The client-side parsers, on whatever arrived.
    let _ = Reply::parse(&message);
    if let Some(text) = Text::parse(&message) {
        let s = text.as_str();
        assert!(s.len() <= TEXT_CAPACITY);
        assert!(s.bytes().all(|b| b == b' ' || b.is_ascii_graphic()));
        check_text_bytes(&text.to_bytes());
    }
    let request = Request::parse(&message).map_err(Notice::from)?;
    let bytes = request.to_bytes();
    let mut original = [0u8; MESSAGE_LEN];
    for (o, b) in original.iter_mut().zip(datagram) {
        *o = *b;
    }
    assert_eq!(
        bytes, original,
        "request does not re-encode to its datagram"
    );
    Ok(request)
}

/// The handler's answer to one datagram.
fn check_reply(datagram: &[u8], expected: Result<Request, Notice>, reply: &[u8; MESSAGE_LEN]) {
    let request = match expected {
        Ok(request) => request,
        Err(notice) => {
            assert_eq!(
                reply,
                &notice.text().to_bytes(),
                "datagram {datagram:02x?}: wrong answer to a non-request"
            );
            return;
        }
    };
    let message = Message::new_checked(&reply[..]).expect("31 bytes");
    if let Ok(r) = Reply::parse(&message) {
        assert_eq!(
            r.command, request.command,
            "reply {reply:02x?} to another command than {request:?}"
        );
        assert!(
            r.values.iter().all(|v| v.is_finite()),
            "non-finite value in reply {r:?} to {request:?}"
        );
        assert!(
            r.index == 0 || r.index == request.index || r.index == request.index & 0x80,
            "reply index {} to {request:?}",
            r.index
        );
        return;
    }
    check_text_bytes(reply);
    let cmd = request.command;
    let mut allowed = vec![
        Notice::Rejected(cmd),
        Notice::BadNumber(cmd),
        Notice::BadIndex(cmd),
        Notice::OutsideWorkspace(cmd),
        Notice::BeyondJointLimit(cmd),
    ];
    match cmd {
        Command::On => allowed.push(Notice::ArmDidNotStart),
        Command::Off => allowed.push(Notice::ArmDidNotStop),
        _ => {}
    }
    assert!(
        allowed.iter().any(|n| &n.text().to_bytes() == reply),
        "answer {:?} to {request:?} is neither its reply nor one of its error texts",
        String::from_utf8_lossy(reply)
    );
}

/// An unsolicited notice from the relay.
fn check_notice(text: &Text) {
    let bytes = text.to_bytes();
    check_text_bytes(&bytes);
    let allowed = [
        Notice::JointLimit,
        Notice::WorkspaceLimit,
        Notice::IkDivergence,
        Notice::ViaPointMissed,
    ];
    assert!(
        allowed.iter().any(|n| n.text() == *text),
        "unexpected unsolicited text {:?}",
        text.as_str()
    );
}

/// `ER`/`WN`, two digits, a space, printable ASCII, a NUL, zeros to the end.
fn check_text_bytes(bytes: &[u8; MESSAGE_LEN]) {
    let end = bytes.iter().position(|&b| b == 0).expect("no NUL");
    assert!(end <= TEXT_CAPACITY, "text {bytes:02x?} too long");
    let (text, tail) = bytes.split_at(end);
    assert!(
        tail.iter().all(|&b| b == 0),
        "text {bytes:02x?} not zero-filled"
    );
    assert!(
        text.iter().all(|&b| b == b' ' || b.is_ascii_graphic()),
        "text {bytes:02x?} not printable"
    );
    assert!(
        text.starts_with(b"ER") || text.starts_with(b"WN"),
        "text {bytes:02x?} is neither ER nor WN"
    );
}
