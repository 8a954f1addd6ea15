//! `[collision]`: the arm's body as capsules, what is checked against what, and the margin
//! (docs/robot-file.md, "`[collision]`"; the model itself: [`Envelope`](super::Envelope)).

use heapless::Vec;
use serde::{Deserialize, Serialize};

use super::error::ConfigReason;
use super::robot::not_negative;
use crate::MAX_JOINTS;

/// Most capsules a robot file may give by hand (`[[collision.capsules]]`).
pub const MAX_CUSTOM_CAPSULES: usize = 8;
/// Most link pairs a robot file may exclude from the self-collision check.
pub const MAX_EXCLUDED_PAIRS: usize = 16;
/// The radius of a link whose joint gives none (m): a forearm-sized tube.
pub const DEFAULT_LINK_RADIUS: f64 = 0.04;

/// The body model's settings; every key has a default, so an absent `[collision]` gives
/// every robot a body: each link's segments along its DH parameters, with radii.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CollisionConfig {
    /// Check the body at all (false: only the tool point is kept in the workspace, as before).
    pub enabled: bool,
    /// The least gap kept between two capsules, and between a capsule and a box or the
    /// bounds' faces (m, ≥ 0; default 0: contact itself is refused, and the checks already
    /// look ahead to where a stop would end).
    pub margin: f64,
    /// The radius of link 0, the base's segments (m, ≥ 0).
    pub base_radius: f64,
    /// The radius of the tool's capsule, from the last joint frame's origin to the tool point
    /// (a sphere there when the tool frame is the last joint frame) (m, ≥ 0).
    pub tool_radius: f64,
    /// Further link pairs never checked against each other (links numbered from 0, the base;
    /// link n carries the tool). Adjacent links are never checked.
    #[serde(deserialize_with = "super::bounded::deserialize")]
    pub exclude: Vec<[u8; 2], MAX_EXCLUDED_PAIRS>,
    /// Capsules by hand: a link with any replaces its segments from the DH parameters by
    /// these.
    #[serde(deserialize_with = "super::bounded::deserialize")]
    pub capsules: Vec<CapsuleConfig, MAX_CUSTOM_CAPSULES>,
}

impl Default for CollisionConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            margin: 0.0,
            base_radius: DEFAULT_LINK_RADIUS,
            tool_radius: 0.03,
            exclude: Vec::new(),
            capsules: Vec::new(),
        }
    }
}

/// One capsule given by hand: a segment in the frame of its link, and a radius.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CapsuleConfig {
    /// The link (0 = base, i = the body joint i moves, frame {i}).
    pub link: u8,
    /// One end, in the link's frame (m).
    pub from: [f64; 3],
    /// The other end (m).
    pub to: [f64; 3],
    /// The radius (m, ≥ 0).
    pub radius: f64,
}

impl CollisionConfig {
    /// Finite, non-negative sizes; links that exist (`links` = joints + 1).
    pub(super) fn validate(&self, links: usize) -> Result<(), (&'static str, ConfigReason)> {
        let sizes = [
            ("collision.margin", self.margin),
            ("collision.base_radius", self.base_radius),
            ("collision.tool_radius", self.tool_radius),
        ];
        for (field, value) in sizes {
            not_negative(value).map_err(|r| (field, r))?;
        }
        let exists = |link: u8| usize::from(link) < links.min(MAX_JOINTS + 1);
        if !self.exclude.iter().flatten().all(|l| exists(*l)) {
            return Err(("collision.exclude", ConfigReason::NoSuchLink));
        }
        for c in &self.capsules {
            if !exists(c.link) {
                return Err(("collision.capsules", ConfigReason::NoSuchLink));
            }
            if c.from.iter().chain(&c.to).any(|v| !v.is_finite()) {
                return Err(("collision.capsules", ConfigReason::NotFinite));
            }
            not_negative(c.radius).map_err(|r| ("collision.capsules", r))?;
        }
        Ok(())
    }
}

/// A joint's `link_radius`, where given, is finite and not negative.
pub(super) fn check_link_radius(radius: Option<f64>) -> Result<(), ConfigReason> {
    radius.map_or(Ok(()), not_negative)
}
