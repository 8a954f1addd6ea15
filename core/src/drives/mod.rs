//! The servo drives: Elmo SimplIQ "Whistle" drives on a CAN bus (spec §6). Their simulation
//! lives in `crate::sim` (feature `sim`).
//!
//! * [`DriveManager`]: the drives' life cycle as a non-blocking state machine, advanced once
//!   per control cycle: start-up, PT set-point streaming, measurement, temperatures, faults,
//!   stop and recalibration.
//! * [`CanBus`]: the CAN controller the manager talks through.
//! * [`JointUnits`]: joint positions ↔ encoder counts (defined with the robot description).
//! * [`DriveFault`]: why the drives stopped, with the client's `ER3x` text.
//! * [`streaming`]: which frames each drive gets per cycle, and the PT flow control.
//! * [`DriveSettings::load_model`]: the bus load ([`crate::config::bus_load`]) with these
//!   settings.
//!
//! docs/drives.md describes the cycle schedule, the state machine, the flow control, the
//! faults and the measured bus figures.

mod bus;
mod drive;
mod emergency;
mod fault;
mod link;
mod manager;
mod retry;
mod settings;
mod startup;
mod state;
pub mod streaming;

pub use crate::config::JointUnits;
pub use bus::{BusState, CanBus, TxError};
pub use emergency::{DriveEmergency, REASON_UNDERFLOW};
pub use fault::{BusFault, DriveFault};
pub use manager::{DriveManager, DriveStats, LifecycleError, UNKNOWN_TEMPERATURE};
pub use settings::{DriveSettings, POSITION_MODE, SetupError};
pub use state::{DriveState, STOP_HOLD_CYCLES};
