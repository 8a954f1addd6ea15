//! What happened during one control tick.

use armgate_protocol::client::{Hit, Hold, Lag};

/// Conditions and happenings of one tick. Conditions (limits, divergence) are raised on every
/// tick while they hold; the message relay decides how often to tell the client.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Events {
    /// The Cartesian set-point or the measured pose is outside the workspace (`ER21`).
    pub workspace_limit: bool,
    /// A joint set-point was clamped to its range (`WN12`).
    pub joint_limit: bool,
    /// A joint set-point step was clamped to the joint's rate limit.
    pub rate_limit: bool,
    /// Tracking IK could not reach the Cartesian set-point (`WN22`).
    pub ik_divergence: bool,
    /// A motion (single move, or the last leg of a sequence) reached its goal.
    pub motion_finished: bool,
    /// A via-point sequence ran to its end.
    pub sequence_finished: bool,
    /// A via-point sequence stopped because a via point was not reached.
    pub sequence_aborted: bool,
    /// A velocity stream holds the arm where its command would drive it on (`WN12 jN at limit
    /// L`, `WN13`): told once when the hold begins.
    pub hold: Option<Hold>,
    /// A joint's measured position was further from its command than the robot file allows:
    /// the arm is stopped (`ER43 jN following error E`), told once.
    pub following_error: Option<Lag>,
    /// A link of the arm, where it is commanded or where a stop begun now would end, came
    /// within the margin of a box, another link or the bounds: the motion stops (`ER21 L3 hits
    /// B1`); raised on the tick the stop begins.
    pub collision: Option<Hit>,
}
