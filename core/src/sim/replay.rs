//! Replaying a recorded exchange through a cycle (host only, feature `std`): the same
//! datagrams at the same times give a transcript, tick by tick, that two shells must agree on
//! (`tools/firmware-e2e.sh` compares `armgate-sim`'s and the firmware's).
//!
//! A recording is text, one datagram per line: its arrival time in microseconds since the
//! cycle started, and its bytes in hex (`#` starts a comment). The replay runs on a virtual
//! clock: every tick on time, a datagram offered to the first tick due at or after its arrival.
//! The transcript has one line per tick: its index and time, the replies and notices it sent
//! (hex), and what the shell says about its drives ([`Replay::run`]'s `drives`).

use std::collections::VecDeque;
use std::fmt::Write as _;
use std::string::String;
use std::vec::Vec;

use super::{SimWhistle, VirtualBus};
use crate::cycle::{Cycle, Datagram, DriveSide, Dropped, Link, Outgoing};
use crate::drives::DriveManager;
use std::format;

/// A recorded exchange.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Replay {
    /// Arrival time (µs) and bytes of each datagram, in arrival order.
    datagrams: VecDeque<(u64, Vec<u8>)>,
}

impl Replay {
    /// Parses a recording; the error names the line.
    pub fn parse(text: &str) -> Result<Self, String> {
        let mut datagrams = VecDeque::new();
        for (n, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or_default().trim();
            if line.is_empty() {
                continue;
            }
            let bad = || format!("line {}: expected `MICROSECONDS HEX`", n + 1);
            let (time, hex) = line.split_once(char::is_whitespace).ok_or_else(bad)?;
            let time: u64 = time.parse().map_err(|_| bad())?;
            let hex = hex.trim();
            let bytes = (0..hex.len() / 2)
                .map(|i| {
                    hex.get(2 * i..2 * i + 2)
                        .and_then(|b| u8::from_str_radix(b, 16).ok())
                })
                .collect::<Option<Vec<u8>>>()
                .filter(|_| hex.len() % 2 == 0)
                .ok_or_else(bad)?;
            datagrams.push_back((time, bytes));
        }
        Ok(Self { datagrams })
    }

    /// Runs `ticks` ticks of `cycle` with the recorded datagrams; the transcript, one line per
    /// tick, ending with what `drives` says about the drives after the tick.
    pub fn run<D: DriveSide>(
        mut self,
        cycle: &mut Cycle<D, ()>,
        ticks: u64,
        drives: impl Fn(&D) -> String,
    ) -> String {
        let mut transcript = String::new();
        for k in 0..ticks {
            let due = cycle.next_due_us();
            let mut link = Port::default();
            while self.datagrams.front().is_some_and(|(t, _)| *t <= due) {
                if let Some((_, bytes)) = self.datagrams.pop_front() {
                    link.waiting.push_back(Datagram::new(&bytes, ()));
                }
            }
            let outcome = cycle.tick(due, &mut link);
            // Requests beyond this tick's batch wait for the next one.
            for datagram in link.waiting.into_iter().rev() {
                self.datagrams
                    .push_front((due, datagram.payload().to_vec()));
            }
            let _ = write!(transcript, "{k} {:.6}", outcome.time);
            for (kind, bytes) in &link.sent {
                let _ = write!(transcript, " {kind}:");
                for b in bytes {
                    let _ = write!(transcript, "{b:02x}");
                }
            }
            let _ = writeln!(transcript, " | {}", drives(cycle.drives()));
        }
        transcript
    }
}

/// The replay's datagram port.
#[derive(Default)]
struct Port {
    waiting: VecDeque<Datagram<()>>,
    sent: Vec<(&'static str, Vec<u8>)>,
}

impl Link<()> for Port {
    fn receive(&mut self) -> Option<Datagram<()>> {
        self.waiting.pop_front()
    }

    fn send(&mut self, datagram: &Datagram<()>, kind: Outgoing) -> Result<(), Dropped> {
        let kind = match kind {
            Outgoing::Reply => "reply",
            Outgoing::Notice => "notice",
        };
        self.sent.push((kind, datagram.payload().to_vec()));
        Ok(())
    }
}

/// What a replay transcript says about CAN drives on the virtual bus after a tick: the drive
/// manager's state, commanded and measured joints, the frames and bits the bus carried so far
/// with a digest of their identifiers and data, and the simulated drives' positions. The same text in every shell, so that they compare.
pub fn can_drives(manager: &DriveManager, bus: &VirtualBus) -> String {
    let stats = bus.stats();
    let positions: Vec<f64> = bus.drives().map(SimWhistle::joint_position).collect();
    format!(
        "{:?} commanded {:?} measured {:?} frames {} bits {} wire {:016x} drives {:?}",
        manager.state(),
        &*manager.commanded(),
        &*manager.measured(),
        stats.frames,
        stats.bits,
        stats.digest,
        positions
    )
}
