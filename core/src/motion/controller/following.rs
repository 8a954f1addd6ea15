//! The following-error fault: every tick the measured joints are compared with the command,
//! and a joint that is further from it than the robot file's `max_following_error` stops the
//! arm (stop cause 9, `ER43 jN following error E`). A drive that cannot keep up (its speed
//! limit below the commanded rate, a blocked joint, a slipping encoder) would otherwise leave
//! the arm somewhere no check had looked at: issue 33's ur5 lagged 4.4 rad behind its
//! commands, its tool 23 mm below the workspace floor, with no fault.

use armgate_protocol::client::Lag;

use super::Controller;
use crate::kinematics::Joints;
use crate::motion::Events;
use crate::motion::supervisor::StopCause;

impl Controller {
    /// Stops the arm if a joint of `q_m` is further from the last command than its limit:
    /// once, until every joint is back within its limit (the stop itself leaves the lag to
    /// the drives to make up, and is not begun again on every tick of it). Nothing while a
    /// stop is already under way, or while nothing is commanded (mode off).
    pub(super) fn check_following(&mut self, q_m: &Joints, events: &mut Events) {
        let Some(command) = &self.command else {
            self.lagging = false;
            return;
        };
        let worst = first_lag(command, q_m, &self.following_limit);
        let Some((joint, error)) = worst else {
            self.lagging = false;
            return;
        };
        if self.lagging || self.supervisor.is_stopping() {
            return;
        }
        self.lagging = true;
        let lag = Lag::new(joint, error);
        events.following_error = Some(lag);
        self.stop(StopCause::FollowingError);
        self.supervisor
            .blame(StopCause::FollowingError, lag.joint.saturating_sub(1));
    }
}

/// The first joint (0-based) whose measured position is further from its command than its
/// limit, and by how much (a NaN difference counts as beyond).
fn first_lag(command: &Joints, measured: &Joints, limit: &Joints) -> Option<(usize, f64)> {
    command
        .iter()
        .zip(measured.iter())
        .zip(limit.iter())
        .map(|((c, m), l)| (libm::fabs(c - m), *l))
        .enumerate()
        .find(|(_, (error, limit))| error > limit || error.is_nan())
        .map(|(joint, (error, _))| (joint, error))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_joint_beyond_its_limit_is_named() {
        let j = |v: &[f64]| Joints::from_slice(v).unwrap();
        let limit = j(&[0.1, 0.1, 0.1]);
        assert_eq!(
            first_lag(&j(&[0.0, 1.0, 2.0]), &j(&[0.05, 1.0, 2.0]), &limit),
            None
        );
        let lag = first_lag(&j(&[0.0, 1.0, 2.0]), &j(&[0.0, 0.8, 1.5]), &limit);
        assert!(matches!(lag, Some((1, e)) if (e - 0.2).abs() < 1e-12));
        let nan = first_lag(&j(&[0.0, 1.0, 2.0]), &j(&[0.0, 1.0, f64::NAN]), &limit);
        assert!(matches!(nan, Some((2, e)) if e.is_nan()));
    }
}
