//! The work budget under a burst (docs/safety.md "Who may command"): eight planning requests
//! to unreachable goals arrive in one tick — a `GT` to a point inside the workspace bounds but
//! out of the arm's reach, three `BG`, each checking the line to it (`motion::reach`) and
//! refused, and the same again to a second such point. The core serves one planning request a
//! tick, so the burst is spread over eight ticks; the worst of them must stay well inside the
//! control period (goal: at most 50 % at 480 MHz).

use armgate_core::cycle::{Datagram, Dropped, Link, Outgoing};
use armgate_protocol::client::{Command, Request, VALUES};

use super::Session;
use crate::counter::{Timing, measure};

/// Planning requests in the burst (the link's requests per tick, `REQUESTS_PER_TICK`).
const BURST: usize = 8;
/// The goals (m), each for half the burst: inside every measured robot's workspace bounds, out
/// of its reach (about 1.7 and 3.3 m from the base), so that the lines cross the reach's edge
/// at different fractions of the way.
const GOALS: [[f32; 3]; 2] = [[1.0, 1.0, 1.0], [1.9, 1.9, 1.9]];
/// Ticks that may serve the burst at most.
const MAX_TICKS: u32 = 4 * BURST as u32;

/// All eight requests waiting in the link at once; replies counted.
struct Burst {
    inbox: [Option<Datagram<()>>; BURST],
    replies: usize,
}

impl Link<()> for Burst {
    fn receive(&mut self) -> Option<Datagram<()>> {
        self.inbox.iter_mut().find_map(Option::take)
    }

    fn send(&mut self, _: &Datagram<()>, kind: Outgoing) -> Result<(), Dropped> {
        if kind == Outgoing::Reply {
            self.replies += 1;
        }
        Ok(())
    }
}

/// The ticks that serve the burst, one window each, in Cartesian mode at rest.
pub(super) fn burst_ticks(session: &mut Session) -> Result<Timing, &'static str> {
    session.request(
        Command::ChangeMode,
        [2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        b"MC",
    )?;
    let half = BURST / 2;
    let inbox = core::array::from_fn(|k| {
        let (command, values) = match GOALS.get(k / half) {
            Some(&[x, y, z]) if k % half == 0 => {
                (Command::GoalRpy, [x, y, z, 0.0, 0.0, 0.0, 0.0])
            }
            _ => (Command::Begin, [0.0; VALUES]),
        };
        let bytes = Request {
            command,
            values,
            index: 0,
        }
        .to_bytes();
        Some(Datagram::new(&bytes, ()))
    });
    let mut link = Burst { inbox, replies: 0 };
    let mut timing = Timing::default();
    while link.replies < BURST && timing.calls < MAX_TICKS {
        session.advance_bus()?;
        let now = session.cycle.next_due_us();
        let (ticks, _) = measure(|| session.cycle.tick(now, &mut link));
        timing.add(ticks);
    }
    if link.replies < BURST {
        return Err("the burst of planning requests was not all answered");
    }
    if session.moving() {
        return Err("a BG to the unreachable goal started a move");
    }
    Ok(timing)
}
