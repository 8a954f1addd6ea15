//! The drive manager's state machine.
//!
//! ```text
//!            start()                 all drives Ready: BG
//!   Idle ──────────► Waking ──► Starting ──────────────────► Operational
//!    ▲                 │  NMT start,  │ per-drive steps          │
//!    │ start()         │  settle      │                          │ stop() or fault
//!  Stopped ◄───────────┴──────────────┴──► Stopping ◄────────────┘
//!    │ fault                 stop()/fault    │ hold point written for
//!    ▼                                       │ STOP_HOLD_CYCLES, then ST
//!  Faulted ◄─────────────────────────────────┘ (if a fault was raised)
//! ```
//!
//! Faulted is also entered directly when the bus cannot carry the stop (bus-off). From Stopped
//! and Faulted, `start()` begins again with the NMT start.

use super::streaming::TARGET_LEAD;

/// Cycles the hold point is written before `ST`: the drive then has executed every point that
/// was queued, and its last segments end at rest on the hold point. Two beyond the lead: the
/// drive's cubic has a zero slope at a knot only when the two knots before it hold the same
/// point (a backward difference, docs/drives.md "PT flow control"), so the drive must pass
/// the second hold point before `ST`.
pub const STOP_HOLD_CYCLES: u32 = TARGET_LEAD + 2;

/// What the drive manager is doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DriveState {
    /// Never started.
    Idle,
    /// Bringing the drives up (NMT start, configuration, PT initialisation).
    Starting,
    /// Streaming set-points: motion is possible.
    Operational,
    /// Bringing the drives to rest on the hold point.
    Stopping,
    /// Stopped on request: the drives hold position under servo.
    Stopped,
    /// Stopped by a fault (see `DriveManager::fault`).
    Faulted,
}

/// The manager's phase, with what each phase counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// Never started.
    Idle,
    /// The NMT start goes out (`None`) or went out and this many cycles remain to wait.
    Waking(Option<u32>),
    /// The drives work through their start steps.
    Starting,
    /// Streaming; the count of streaming cycles so far.
    Streaming(u32),
    /// Writing the hold point; `ST` goes out when the count reaches zero.
    Stopping(u32),
    /// Stopped on request.
    Stopped,
    /// Stopped by a fault.
    Faulted,
}

impl Phase {
    /// The public state.
    pub fn state(self) -> DriveState {
        match self {
            Self::Idle => DriveState::Idle,
            Self::Waking(_) | Self::Starting => DriveState::Starting,
            Self::Streaming(_) => DriveState::Operational,
            Self::Stopping(_) => DriveState::Stopping,
            Self::Stopped => DriveState::Stopped,
            Self::Faulted => DriveState::Faulted,
        }
    }

    /// The phase after `start()`, or `None` if already running.
    pub fn start(self) -> Option<Self> {
        match self {
            Self::Idle | Self::Stopped | Self::Faulted => Some(Self::Waking(None)),
            Self::Waking(_) | Self::Starting | Self::Streaming(_) | Self::Stopping(_) => None,
        }
    }

    /// The phase after `stop()`, or `None` if not running.
    pub fn stop(self) -> Option<Self> {
        match self {
            Self::Waking(_) | Self::Starting | Self::Streaming(_) => {
                Some(Self::Stopping(STOP_HOLD_CYCLES))
            }
            Self::Idle | Self::Stopping(_) | Self::Stopped | Self::Faulted => None,
        }
    }

    /// The phase after a fault; `can_send` is false if the bus cannot carry a stop.
    pub fn fault(self, can_send: bool) -> Self {
        match self {
            Self::Waking(_) | Self::Starting | Self::Streaming(_) if can_send => {
                Self::Stopping(STOP_HOLD_CYCLES)
            }
            Self::Stopping(n) if can_send => Self::Stopping(n),
            _ => Self::Faulted,
        }
    }
}
