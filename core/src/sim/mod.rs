//! Simulations, kept apart from the product code: what an arm, its drives and their bus would
//! do, so that the whole controller runs on a desk, in tests and in the firmware's `sim-drives`
//! build.
//!
//! * [`IdealArm`], [`RateLimitedArm`]: arms that follow joint commands.
//! * [`SimulatedDrives`]: drives without a bus, a simulated arm behind the
//!   [`Drives`](crate::command::Drives) interface.
//! * [`SimWhistle`]: an Elmo SimplIQ "Whistle" drive on CAN (NMT, SDO, the binary interpreter,
//!   the PT table, a servo loop, and for PDO streaming SYNC, RPDO3/TPDO3 mapped by SDO and a
//!   group id).
//! * [`VirtualBus`]: a CAN bus with simulated Whistles on it, bit-timed with arbitration, with
//!   random frame loss and drive clock errors to inject.
//! * [`BodyOracle`]: the whole-arm invariant the stop bench, the fuzz target and the stop tests
//!   hold every commanded pose to (no link enters a box or another link).

mod arm;
mod body_oracle;
mod bus;
mod drives;
#[cfg(feature = "std")]
pub mod replay;
pub mod whistle;

pub use arm::{IdealArm, RateLimitedArm};
pub use body_oracle::{BodyOracle, Entry};
pub use bus::{BusStats, Stalled, VirtualBus};
pub use drives::{ArmModel, SimulatedDrives};
pub use whistle::{SimWhistle, WhistleConfig, WhistleFaults, WhistleStats};
