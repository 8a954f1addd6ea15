//! Motion: trajectory generation, via-point sequences, limiters, the mode switch and the
//! control step that runs them in a fixed order.
//!
//! * [`Trapezoid`], [`StraightLine`]: profiles (spec §4.1).
//! * [`DoubleS`], [`JerkLimits`]: jerk-limited (double-S) profiles, beyond the seed.
//! * [`JointGenerator`], [`CartesianGenerator`], [`Shape`]: set-point sources (§4.2, §4.3, §4.5).
//! * [`Sequence`]: via points (§4.4), stopping at each or blending through it within a
//!   tolerance (`blend.rs`, beyond the seed: the next leg superposed on the running one).
//! * [`JointLimiter`], [`Workspace`]: limits (§5.1, §5.2); [`Body`]: the whole arm inside
//!   the envelope (capsules against boxes, bounds and each other), beyond the seed.
//! * [`Controller`]: the mode switch (§5.3) and the tick (§1.4); its supervisor
//!   (`supervisor.rs`) owns every transition to rest ([`StopCause`]).
//! * [`VelocityStream`]: twist and joint-rate streaming (`TW`, `jW`), beyond the seed.

mod blend;
mod body;
mod brake;
mod cartesian_generator;
mod controller;
mod events;
mod fixed_point;
mod joint_generator;
mod joint_limiter;
mod joint_path;
mod joint_stop;
mod profile;
mod reach;
mod refusal;
mod sequence;
mod shape;
mod straight_line;
mod supervisor;
mod trapezoid;
mod velocity_stream;
mod workspace;

pub use body::{Body, CHECKS_PER_SECOND};
pub use cartesian_generator::CartesianGenerator;
pub use controller::{CartesianPlan, Controller, Mode, StepOutput};
pub use events::Events;
pub use joint_generator::JointGenerator;
pub use joint_limiter::{JointLimiter, Limited};
pub use profile::{DoubleS, JerkLimits, NEWTON_ITERATIONS, ProfileError, RandomCase};
pub use reach::{
    CHECK_ITERATIONS, LINE_SAMPLES, MAX_JOINT_STEP, POINT_WORK, SOLVES_PER_LINE, check_iterations,
};
pub use refusal::Refusal;
pub use sequence::{Sequence, SequenceStep, Tolerances, VIA_SLOTS, ViaPoint};
pub use shape::Shape;
pub use straight_line::StraightLine;
pub use supervisor::{StopCause, latches};
pub use trapezoid::Trapezoid;
pub use velocity_stream::{
    MARGIN_SHARE, MAX_DAMPING, SINGULAR_THRESHOLD, StreamCommand, StreamStep, TIMEOUT_PERIODS,
    VelocityStream,
};
pub use workspace::Workspace;
