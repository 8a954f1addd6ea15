//! The control cycle: what happens once per control period, the same in every shell.
//!
//! [`Cycle`] owns the [`CommandHandler`](crate::command::CommandHandler) (and through it the controller) and the drives
//! ([`DriveSide`]: the CANopen drive manager on a [`CanBus`](crate::drives::CanBus), or a
//! simulated arm). A shell — `armgate-sim`, the firmware on the board or on Linux, the QEMU
//! benchmark, the examples, the test rigs, the fuzz target — only moves bytes and time: it
//! waits until [`Cycle::next_due_us`], then calls [`Cycle::tick`] with its clock and its
//! datagram port ([`Link`]). The CAN frames pass through the bus the drive side owns.
//!
//! One tick, in this order:
//!
//! 1. **late ticks**: every tick runs at its place on the schedule, time `k × period`, never a
//!    clock reading, so every shell computes the same. A shell that is late runs the missed
//!    ticks back to back (counted): the drives play one PT point per period from their
//!    buffers, and a point never sent is a buffer underflow (`ER33`) a few periods later. More
//!    than [`MAX_CATCH_UP`] periods behind, the missed ticks are skipped (counted) and the
//!    schedule goes on from the present. On the board the watchdog resets long before that;
//!    a burst the CAN transmit queue cannot take is the drive fault `ER35`, never silent;
//! 2. **drives in**: the bus is brought up to the tick's time (a simulated bus runs its drives
//!    here), the drive manager takes the received frames;
//! 3. **control step** on the measured joints (`CommandHandler::tick`). A measurement that does
//!    not fit the arm (the step's error) makes the drives hold and is counted, never fatal;
//! 4. **drives out**: the manager queues the cycle's frames (set-points, queries, heartbeat);
//!    it never waits on the bus;
//! 5. **requests**: the signature checks first ([`Signing`]: with a key, an unsigned, forged,
//!    replayed or cut-off datagram is dropped and counted, never answered); then at most [`REQUESTS_PER_TICK`] waiting client datagrams are handled, in
//!    arrival order, each answered at once through the link; more wait for the next tick, so
//!    a tick's work stays bounded (a reply waits at most about a period). They come after the
//!    step, so that every reply reflects this tick's measurement (also the very first tick's)
//!    and a motion they start runs from the next tick on;
//!    At most [`PLANNING_PER_TICK`] of them may plan a motion (a move, a sequence, a
//!    recalibration, a Cartesian goal): the others, and what their clients send after them,
//!    wait for the next ticks; a stop cancels them (module `budget`);
//! 6. **notices**: every unsolicited warning the relay holds goes to the client that holds the
//!    arm, or with none to the last client that sent a valid request
//!    ([`Session`](crate::command::Session)), signed if its request was; with none yet, it is
//!    counted and dropped.
//!
//! Bus-off: the drive manager latches it as fault `ER35` and stops; the client's `ON` clears
//! it — [`CanDrives`] first asks the bus to recover ([`CanBus::recover`](crate::drives::CanBus::recover)),
//! then restarts the drives. docs/architecture.md shows the cycle and the shells.

mod budget;
mod can_drives;
mod counters;
mod flash_log;
mod link;
mod links;
mod replay;
mod shares;
mod side;
mod signing;
#[cfg(feature = "std")]
mod state_file;
mod tick;

pub use budget::{LINE_SLICE, PLANNING_PER_TICK, SEARCH_SLICE};
pub use can_drives::CanDrives;
pub use counters::CycleCounters;
pub use flash_log::{FlashLog, FlashSectors, RECORD_LEN};
pub use link::{Datagram, Dropped, Link, Outgoing, Peer};
pub use links::{LINKS, SHARED_WITHIN};
pub use replay::{FIRST_WINDOW, RESERVE_AHEAD, ReplayStore, Unkept};
pub use shares::{Shares, answers_a_stop, goes_ahead};
pub use side::DriveSide;
pub use signing::{Signing, UnknownAccess, UnsignedAccess};
#[cfg(feature = "std")]
pub use state_file::StateFile;
pub use tick::{Cycle, MAX_CATCH_UP, REQUESTS_PER_TICK, TickOutcome};
