//! Jerk-limited (double-S, seven-phase) rest-to-rest profiles, Ruckig style: one concept per
//! file.
//!
//! * [`JerkLimits`] (`limits.rs`): the velocity, acceleration and jerk bounds of one axis.
//! * [`DoubleS`] (`double_s.rs`): the profile from 0 to a signed distance, sampled as
//!   position, velocity and acceleration at a time.
//! * `phases.rs`: the closed-form phase durations: minimum time, and stretched to a longer
//!   duration for time synchronisation.
//! * [`ProfileError`] (`error.rs`): why a profile could not be built.
//! * [`RandomCase`] (`random_case.rs`): the random requests of the tests and benchmarks.
//!
//! Usage: `DoubleS::new(distance, limits, min_duration)` plans the profile that lasts
//! `max(minimum time, min_duration)`. To synchronise several axes, plan each with
//! `min_duration = 0`, take the longest [`DoubleS::duration`] and rebuild the others with
//! [`DoubleS::with_duration`]; all then start and stop together, each within its own limits.
//! [`DoubleS::sample`] gives `(position, velocity, acceleration)` at a time since the start:
//! rest at 0 before, rest at the distance from [`DoubleS::duration`] on. Planning has no loop
//! except a Newton iteration bounded by a count (stretching without reaching the acceleration
//! limit), never allocates and never panics; docs/motion.md has the math and the figures.

mod double_s;
mod error;
mod limits;
mod phases;
mod random_case;

pub use double_s::DoubleS;
pub use error::ProfileError;
pub use limits::JerkLimits;
pub use phases::NEWTON_ITERATIONS;
pub use random_case::RandomCase;
