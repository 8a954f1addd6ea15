//! The work budget under a burst (docs/safety.md "Who may command"): eight planning requests
//! to unreachable goals arrive in one tick — a `GT` to a point inside the workspace bounds but
//! out of the arm's reach, three `BG`, each checking the line to it (`motion::reach`) and
//! refused, and the same again to a second such point. The core serves one planning request a
//! tick, and a `BG`'s line check a slice a tick, so the burst is spread over many ticks; the
//! worst of them must stay well inside the control period (goal: at most 50 % at 480 MHz).
//! Measured on every embedded robot.

use armgate_core::config::{JointType, RobotConfig};
use armgate_core::cycle::{Datagram, Dropped, Link, Outgoing};
use armgate_protocol::client::{Command, Request, VALUES};

use super::Session;
use crate::counter::{Timing, measure};

/// Planning requests in the burst (the link's requests per tick, `REQUESTS_PER_TICK`).
const BURST: usize = 8;
/// Ticks that may serve the burst at most (each `BG`'s line check runs a slice a tick).
const MAX_TICKS: u32 = 2_000;
/// The reply of the first `BG` to each goal, kept to show why it was refused.
const FIRST_BEGINS: [usize; 2] = [1, 1 + BURST / 2];

/// What the burst cost and why its first `BG`s were refused.
pub(super) struct Burst {
    /// One window per tick that served it.
    pub timing: Timing,
    /// The goals (m).
    pub goals: [[f32; 3]; 2],
    /// The answers to the first `BG` to each goal (31 bytes, an ER text).
    pub refusals: [[u8; 31]; 2],
}

/// An upper bound on the arm's reach from its base frame's origin (m): every link length and
/// offset stretched out in a line, a prismatic joint at its longer end.
fn reach_bound(config: &RobotConfig) -> f64 {
    let links: f64 = config
        .joints
        .iter()
        .map(|j| match j.kind {
            JointType::Revolute => j.a.abs() + j.d.abs(),
            JointType::Prismatic => j.a.abs() + (j.d + j.min).abs().max((j.d + j.max).abs()),
        })
        .sum();
    let [x, y, z] = config.tool.xyz;
    links + config.tool.a.abs() + config.tool.d.abs() + libm::sqrt(x * x + y * y + z * z)
}

/// The two goals (m), each for half the burst: on the line from the base frame's origin to the
/// workspace bounds' upper corner, inside the bounds and out of reach: 5 % beyond
/// [`reach_bound`] (most of the line is reachable: the check works through most of it before it
/// fails), and at 95 % of the way to the corner (it fails earlier).
pub(super) fn goals(config: &RobotConfig) -> [[f32; 3]; 2] {
    let [x0, y0, z0] = config.base.xyz;
    let [_, x_max, _, y_max, _, z_max] = config.workspace.bounds;
    let [dx, dy, dz] = [x_max - x0, y_max - y0, z_max - z0];
    let length = libm::sqrt(dx * dx + dy * dy + dz * dz);
    let beyond = (1.05 * reach_bound(config) / length).min(0.9);
    [beyond, 0.95].map(|f| [x0 + f * dx, y0 + f * dy, z0 + f * dz].map(|v| v as f32))
}

/// All eight requests waiting in the link at once; replies kept.
struct BurstLink {
    inbox: [Option<Datagram<()>>; BURST],
    replies: usize,
    refusals: [[u8; 31]; 2],
}

impl Link<()> for BurstLink {
    fn receive(&mut self) -> Option<Datagram<()>> {
        self.inbox.iter_mut().find_map(Option::take)
    }

    fn send(&mut self, datagram: &Datagram<()>, kind: Outgoing) -> Result<(), Dropped> {
        if kind == Outgoing::Reply {
            if let Some(k) = FIRST_BEGINS.iter().position(|&n| n == self.replies)
                && let (Some(kept), Some(bytes)) = (
                    self.refusals.get_mut(k),
                    datagram.payload().get(..31),
                )
            {
                kept.copy_from_slice(bytes);
            }
            self.replies += 1;
        }
        Ok(())
    }
}

/// The ticks that serve the burst, one window each, in Cartesian mode at rest.
pub(super) fn burst_ticks(
    session: &mut Session,
    config: &RobotConfig,
) -> Result<Burst, &'static str> {
    session.request(
        Command::ChangeMode,
        [2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        b"MC",
    )?;
    let goals = goals(config);
    let half = BURST / 2;
    let inbox = core::array::from_fn(|k| {
        let (command, values) = match goals.get(k / half) {
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
    let mut link = BurstLink {
        inbox,
        replies: 0,
        refusals: [[0; 31]; 2],
    };
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
        return Err("a BG to an unreachable goal started a move");
    }
    Ok(Burst {
        timing,
        goals,
        refusals: link.refusals,
    })
}
