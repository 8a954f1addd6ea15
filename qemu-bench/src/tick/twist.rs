//! The tick while a client streams a twist (`TW`, docs/motion.md "Twist and joint-velocity
//! streaming"): every tick carries one `TW` (a client streaming once per control period), so
//! the window holds the request's handling and the stream's step — FK, Jacobian, singular-value
//! estimate, damped pseudo-inverse, joint-limit braking, ramp, workspace look-ahead, limiter.

use armgate_protocol::client::Command;

use super::Session;
use crate::counter::Timing;

/// Ticks measured, each with one `TW`.
const TICKS: u32 = 200;
/// The twist reverses every this many ticks, so that the ramps are measured too.
const REVERSE_EVERY: u32 = 50;
/// 1 cm/s along z and 0.02 rad/s about x (base frame).
const TWIST: [f32; 7] = [0.0, 0.0, 0.01, 0.02, 0.0, 0.0, 0.0];

/// Switches to Cartesian mode (a no-op after a Cartesian move) and measures the streaming ticks.
pub(super) fn streaming_ticks(session: &mut Session) -> Result<Timing, &'static str> {
    session.request(
        Command::ChangeMode,
        [2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        b"MC",
    )?;
    let mut timing = Timing::default();
    for k in 0..TICKS {
        let sign = if (k / REVERSE_EVERY).is_multiple_of(2) {
            1.0
        } else {
            -1.0
        };
        timing.add(session.request(Command::Twist, TWIST.map(|v| v * sign), b"WT")?.0);
    }
    Ok(timing)
}
