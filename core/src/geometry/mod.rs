//! Distances between the shapes the arm's envelope is made of: segments, capsules (a segment
//! with a radius) and axis-aligned boxes. Exact closed forms, no allocation, no panic, every
//! loop bounded: the control tick runs them for every pair of links, twice a tick
//! (docs/safety.md, "The whole arm inside the envelope").
//!
//! * [`segment_segment`]: the closest distance of two segments (degenerate ones included).
//! * [`segment_box`]: the closest distance of a segment to a box (0 if it meets the box).
//! * [`Capsule`]: capsule–capsule, capsule–box and capsule-inside-bounds clearances.

mod capsule;
mod distance;

pub use capsule::Capsule;
pub use distance::{Segment, point_box, segment_box, segment_segment};
