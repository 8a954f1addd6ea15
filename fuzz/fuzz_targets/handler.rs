//! Fast fuzz target: the protocol parser, the command handling and the drive manager's frame
//! handling, without simulated time. Beside `datagram` (the whole cycle over simulated
//! Whistles at their 360 µs sample time, a few dozen inputs a second), this one runs thousands.
//!
//! Input format (`datagram`'s without its signed chunks; every byte string is valid): a sequence of chunks,
//! each one header byte `h`:
//!
//! * bits 0–1: control ticks run after the chunk: 0, 1, 1 or 2 (at most [`MAX_TICKS`] per
//!   input);
//! * bit 2 clear: a **datagram** of `h >> 3` bytes (0..=31; fewer if the input ends first),
//!   answered at once by the command handler;
//! * bit 2 set: a **CAN frame** the drive manager receives: bits 3–6 are the data length
//!   (capped at 8), then two bytes of identifier (little-endian, 11 bits), then the data.
//!
//! Every input starts from the same state: `robots/ranger-mk1.toml`'s command handler and the
//! drive manager just started, on a bus that delivers only the fuzzer's frames and drops what
//! the manager sends. A tick is the cycle's order: the manager receives, the handler steps,
//! the manager transmits. Checked as in `datagram` (`checks.rs`): every answer, every notice,
//! every command finite and within the joint limits.
#![no_main]

use std::collections::VecDeque;
use std::sync::OnceLock;

use armgate_core::command::CommandHandler;
use armgate_core::config::{ValidRobot, load_file};
use armgate_core::cycle::CanDrives;
use armgate_core::drives::{BusState, CanBus, DriveSettings, TxError};
use armgate_protocol::can::CanFrame;
use libfuzzer_sys::fuzz_target;

mod checks;
use checks::{check_notice, check_parsers, check_reply};

/// Ticks run after a chunk, by header bits 0–1.
const TICKS: [u32; 4] = [0, 1, 1, 2];
/// Ticks per input at most.
const MAX_TICKS: u32 = 16;

/// The robot file, relative to the fuzz crate.
const ROBOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../robots/ranger-mk1.toml");

/// A bus that delivers the fuzzer's frames and accepts every frame sent.
#[derive(Clone, Default)]
struct ScriptBus {
    injected: VecDeque<CanFrame>,
}

impl CanBus for ScriptBus {
    fn try_transmit(&mut self, _frame: &CanFrame) -> Result<(), TxError> {
        Ok(())
    }

    fn try_receive(&mut self) -> Option<CanFrame> {
        self.injected.pop_front()
    }

    fn state(&self) -> BusState {
        BusState::ErrorActive
    }
}

/// One chunk of an input (the format is in each target's docs).
pub enum Chunk<'a> {
    /// A client datagram, 0..=31 bytes.
    Datagram(&'a [u8]),
    /// A CAN frame for the drive manager (none if its bytes make no frame).
    Frame(Option<CanFrame>),
}

/// The chunks of `data`, each with its header's bits 0–1 (which ticks follow it).
pub fn chunks(mut data: &[u8]) -> impl Iterator<Item = (usize, Chunk<'_>)> {
    std::iter::from_fn(move || {
        let (&header, rest) = data.split_first()?;
        let chunk = if header & 0b100 == 0 {
            let len = usize::from(header >> 3);
            let (datagram, rest) = rest.split_at(len.min(rest.len()));
            data = rest;
            Chunk::Datagram(datagram)
        } else {
            let len = usize::from((header >> 3) & 0x0F).min(8);
            let (frame, rest) = rest.split_at((2 + len).min(rest.len()));
            data = rest;
            Chunk::Frame(match frame {
                [lo, hi, bytes @ ..] => {
                    CanFrame::new(u16::from_le_bytes([*lo, *hi]) & 0x7FF, bytes).ok()
                }
                _ => None,
            })
        };
        Some((usize::from(header & 0b11), chunk))
    })
}

#[derive(Clone)]
struct State {
    config: ValidRobot,
    handler: CommandHandler,
    drives: CanDrives<ScriptBus>,
    now: f64,
}

fn start() -> &'static State {
    static START: OnceLock<State> = OnceLock::new();
    START.get_or_init(|| {
        let config: ValidRobot = load_file(ROBOT).unwrap_or_else(|e| panic!("{ROBOT}: {e}"));
        let drives = CanDrives::started(&config, &DriveSettings::default(), ScriptBus::default())
            .expect("drives");
        State {
            handler: CommandHandler::new(&config),
            drives,
            now: 0.0,
            config,
        }
    })
}

impl State {
    /// One tick in the cycle's order, its command checked and its notices too.
    fn tick(&mut self) {
        let (manager, bus) = self.drives.split_mut();
        manager.receive(bus);
        let measured = manager.measured();
        let out = self.handler.tick(self.now, &measured, &mut self.drives);
        let command = out.ok().and_then(|out| out.command);
        if let Some(cmd) = &command {
            assert!(
                cmd.is_finite(),
                "t {}: non-finite command {cmd:?}",
                self.now
            );
            assert!(
                self.handler.controller().chain().within_limits(cmd),
                "t {}: command beyond the joint limits {cmd:?}",
                self.now
            );
        }
        let (manager, bus) = self.drives.split_mut();
        manager.transmit(self.now, command.as_ref(), bus);
        while let Some(notice) = self.handler.next_notice() {
            check_notice(&notice.to_bytes());
        }
        self.now += self.config.control_period;
    }
}

fuzz_target!(|data: &[u8]| {
    let mut state = start().clone();
    let mut ticks = 0u32;
    for (after, chunk) in chunks(data) {
        match chunk {
            Chunk::Datagram(datagram) => {
                let expected = check_parsers(datagram);
                let reply = state.handler.handle(datagram, &mut state.drives);
                check_reply(datagram, expected, &reply);
            }
            Chunk::Frame(frame) => state.drives.bus_mut().injected.extend(frame),
        }
        for _ in 0..TICKS[after] {
            if ticks >= MAX_TICKS {
                break;
            }
            ticks += 1;
            state.tick();
        }
    }
});
