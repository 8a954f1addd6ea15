//! The per-tick work budget: at most [`PLANNING_PER_TICK`] planning request a tick.
//!
//! A planning request (`BG`, `VE`, `jB`, `jE`, `RC`, the Cartesian goals and via points
//! `GL`, `GT`, `VP`, and the closed-form IK's `KG` and `KS`) may run the IK along a whole line:
//! about 1.5 M instructions to an unreachable goal on the board (`KS` on a calibrated arm near
//! a singularity searches for missed solutions, up to 8 Newton descents). Eight in one tick
//! would take several periods and let the drives' buffers run dry, so the second and later
//! planning requests of a tick wait for the next ticks ([`Waiting`]), and so does everything
//! after them from the same client (its requests keep their order). Other clients' requests go
//! on meanwhile. A stop (`ST`, `jR`), from anyone, never waits, not even behind its own
//! client's requests: it is handled at once and cancels the requests still waiting that would
//! start motion (the planning ones and the streams `TW`, `jW`), which arrived before it: each
//! is answered `ER42 Cmd XX cancelled by ST` rather than started after the stop.
//!
//! `KG` on a chain without a closed form searches globally: up to `ik.global_iterations`
//! (at most 65,535) Newton steps to a goal out of reach, 10.5 M Cortex-M7 instructions at the
//! default 2,000. That search runs in slices of [`SEARCH_SLICE`] steps, one a tick in the
//! tick's planning slot, and the `KG` is answered when it ends; meanwhile the other planning
//! requests wait, and so does everything from its client, as behind a waiting request. A stop
//! cancels it as it cancels the requests waiting.
//!
//! `BG`'s and `VE`'s line check (every point of a line checked for the whole arm's body) runs
//! the same way, in slices of [`LINE_SLICE`] work (a few points): the one mechanism is the
//! handler's work in slices (`command/handler/planning.rs`, [`Slice`]) in this planning slot.

use armgate_protocol::client::{Command, Message, Request};
use heapless::Deque;

use super::link::{Datagram, Peer};
use super::tick::REQUESTS_PER_TICK;
use crate::command::{Class, Slice};

/// Planning requests handled per tick at most.
pub const PLANNING_PER_TICK: usize = 1;

/// Newton steps of a `KG`'s global search per tick at most: four attempts, at most 0.53 M
/// Cortex-M7 instructions (qemu-bench, "KG slice"), less than one planning request of a line
/// may take.
pub const SEARCH_SLICE: u16 = 120;

/// The work of a `BG`'s or `VE`'s line check per tick: a point of a line (its solve, the whole
/// arm's check there) counts `motion::POINT_WORK` = 2, and each Newton iteration of its solve 1
/// more; a point is begun while any is left. Five points that the closed form solves, two that
/// need a few Newton steps; about 50,000 Cortex-M7 instructions a slice on average (qemu-bench,
/// "line check slice"; docs/kinematics.md).
pub const LINE_SLICE: u16 = 10;

/// The work of a planning request a tick.
pub(super) const SLICE: Slice = Slice {
    steps: SEARCH_SLICE,
    line_work: LINE_SLICE,
};

/// What a request costs, as the budget sees it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Work {
    /// May plan a motion (counted against the budget).
    Plans(Command),
    /// Streams a velocity: not counted, but cancelled by a stop as a planning request is.
    Streams(Command),
    /// Stops the arm (cancels the planning requests and streams waiting).
    Stops,
    /// Anything else (or not a request at all: answered with its refusal).
    Other,
}

impl Work {
    /// The work of a datagram.
    pub(super) fn of(datagram: &[u8]) -> Self {
        let Ok(request) = Message::new_checked(datagram).and_then(|m| Request::parse(&m)) else {
            return Self::Other;
        };
        match request.command {
            c @ (Command::Begin
            | Command::ViaExecute
            | Command::JointBegin
            | Command::JointExecute
            | Command::Recalibrate
            | Command::GoalQuaternion
            | Command::GoalRpy
            | Command::IkGoal
            | Command::IkSolution
            | Command::ViaPoint) => Self::Plans(c),
            c @ (Command::Twist | Command::JointVelocity) => Self::Streams(c),
            c if Class::of(c) == Class::Stop => Self::Stops,
            _ => Self::Other,
        }
    }
}

/// A request past the signature check: the message, its client, and its link id if it came
/// signed (its reply is sealed alike).
#[derive(Clone, Copy, Debug)]
pub(super) struct Pending<P> {
    pub datagram: Datagram<P>,
    pub link: Option<u8>,
}

/// Requests that wait for a later tick, in arrival order.
pub(super) type Waiting<P> = Deque<Pending<P>, REQUESTS_PER_TICK>;

/// True if a request from `peer` waits in `waiting` (its next one must wait behind it).
pub(super) fn waits<P: Peer>(waiting: &Waiting<P>, peer: P) -> bool {
    waiting
        .iter()
        .any(|p| p.datagram.peer.address() == peer.address())
}

impl Work {
    /// The command of a request a stop cancels while it waits: one that would start motion.
    pub(super) fn cancelled_by_stop(self) -> Option<Command> {
        match self {
            Self::Plans(c) | Self::Streams(c) => Some(c),
            Self::Stops | Self::Other => None,
        }
    }
}

/// Takes the requests a stop cancels out of `waiting` (the others stay, in order), calling
/// `cancel` for each.
pub(super) fn cancel_motion<P: Copy>(waiting: &mut Waiting<P>, mut cancel: impl FnMut(Pending<P>)) {
    for _ in 0..waiting.len() {
        let Some(request) = waiting.pop_front() else {
            break;
        };
        if Work::of(request.datagram.payload())
            .cancelled_by_stop()
            .is_some()
        {
            cancel(request);
        } else {
            // Room: it was just taken out.
            let _ = waiting.push_back(request);
        }
    }
}
