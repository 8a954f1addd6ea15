//! Set-point streaming in position mode: which frames each drive gets per cycle
//! ([`Schedule`]) and how PT points are written and paced by the drive's read index
//! ([`PtStream`], interpreter schedule) or by the PT pointers of its transmit PDO
//! ([`PdoStream`], PDO schedule).

mod adaptive;
mod pdo;
mod pt;
mod schedule;
mod stream;

pub use adaptive::{AdaptiveLead, LeadChange, PDO_LEAD_RAISE};
pub use pdo::PdoStream;
pub use pt::{FILLED_POINTS, FlowError, PtStream, TARGET_LEAD};
pub use schedule::{Query, Schedule};
pub use stream::Stream;
