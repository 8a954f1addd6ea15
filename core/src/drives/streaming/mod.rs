//! Set-point streaming in position mode: which frames each drive gets per cycle
//! ([`Schedule`]) and how PT points are written and paced by the drive's read index
//! ([`PtStream`]).

mod pt;
mod schedule;

pub use pt::{FILLED_POINTS, FlowError, PtStream, TARGET_LEAD};
pub use schedule::{Query, Schedule};
