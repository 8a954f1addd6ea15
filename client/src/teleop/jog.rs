//! Jogging with held keys: a key press streams a velocity (`TW`/`jW`) until shortly after the
//! terminal's last auto-repeat of that key, so a held key moves the arm smoothly and a
//! release lets it ramp to rest.
//!
//! A terminal reports a held key as a press, a pause (the auto-repeat delay, typically
//! 250–600 ms), then repeats every 30–50 ms; most do not report the release. So the first
//! press holds for [`FIRST_HOLD`], each repeat for [`REPEAT_HOLD`] from then on. Terminals that
//! speak the kitty keyboard protocol are asked for releases too, and a release stops the stream
//! at once.

use std::time::{Duration, Instant};

use crate::Velocity;

/// How long a first press streams: covers the terminal's auto-repeat delay, so a held key
/// does not pause before its repeats begin (a tap jogs this long).
pub const FIRST_HOLD: Duration = Duration::from_millis(600);

/// How long a repeat streams: a few auto-repeat intervals.
pub const REPEAT_HOLD: Duration = Duration::from_millis(120);

/// Cartesian jog speed per unit of scale (m/s).
pub const BASE_JOG_SPEED: f64 = 0.005;

/// Joint jog rate per unit of scale (rad/s, or m/s for prismatic joints).
pub const BASE_JOG_RATE: f64 = 0.02;

/// The key being held: what it streams and when it was last pressed.
#[derive(Clone, Debug, Default)]
pub struct HeldKey {
    last: Option<(Velocity, Instant)>,
}

impl HeldKey {
    /// A press of a key that streams `velocity` at `now`: until when to stream it.
    pub fn press(&mut self, velocity: Velocity, now: Instant) -> Instant {
        let repeat = self.last.as_ref().is_some_and(|(v, at)| {
            *v == velocity && now.saturating_duration_since(*at) <= FIRST_HOLD
        });
        self.last = Some((velocity, now));
        now + if repeat { REPEAT_HOLD } else { FIRST_HOLD }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_presses_hold_through_the_repeat_delay_and_repeats_briefly() {
        let mut held = HeldKey::default();
        let t0 = Instant::now();
        let left = Velocity::Joints(vec![-0.02, 0.0]);
        let right = Velocity::Joints(vec![0.02, 0.0]);
        assert_eq!(held.press(left.clone(), t0), t0 + FIRST_HOLD);
        let t1 = t0 + Duration::from_millis(500);
        assert_eq!(held.press(left.clone(), t1), t1 + REPEAT_HOLD);
        // Another key starts afresh, and so does the same key after a pause.
        assert_eq!(held.press(right, t1), t1 + FIRST_HOLD);
        let t2 = t1 + Duration::from_secs(2);
        assert_eq!(held.press(left, t2), t2 + FIRST_HOLD);
    }
}
