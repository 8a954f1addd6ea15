//! The `[motion]` table: how the generators shape their moves.

use serde::{Deserialize, Serialize};

/// Motion settings; an absent `[motion]` table gives the seed's behaviour.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MotionConfig {
    /// The velocity profile of Cartesian straight lines and joint moves.
    pub profile: ProfileKind,
}

/// The velocity profile the generators plan with.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ProfileKind {
    /// The seed's trapezoid (spec §4.1): acceleration jumps between 0 and its limit.
    #[default]
    Trapezoid,
    /// Double-S (seven phases): acceleration ramps within `max_jerk`, which every joint and
    /// `[cartesian]` must then give.
    JerkLimited,
}
