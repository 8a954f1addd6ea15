//! The motion supervisor: the end of the pipeline, which owns every transition to rest.
//!
//! Every stop — `ST`, a mode change or `OF` while moving, the workspace, IK divergence — goes
//! through [`Supervisor::begin`] and then one [`Brake`] per tick until the arm is at rest:
//!
//! * **along the path** while the generator can still be followed: its motion time advances
//!   by `scale × period`, the scale falling within the joints' acceleration (and jerk) limits
//!   and, for Cartesian motions, the Cartesian ones, so the tool stays on its line or shape;
//! * **in joint space** otherwise (a mode change, IK divergence, a stream): a [`JointStop`]
//!   ramps out the acceleration the arm had (where jerk is limited) and scales the commanded
//!   joint velocity down to zero, every joint by the same fraction.
//!
//! The supervisor also remembers the last commanded joint velocity, which the joint limiter
//! needs for its acceleration clamp, the last clamp before the drives.

use super::brake::Brake;
use super::joint_stop::{JointStop, StopLimits};
use crate::config::ValidRobot;
use crate::kinematics::Joints;
use armgate_protocol::client::Hold;
pub use armgate_protocol::client::StopCause;

/// True if a stop of `cause` latches: afterwards the arm stays at rest until its holder starts
/// a motion on purpose (a move, or a zero twist or zero joint rates that re-arm a stream), so
/// that a stream still being sent cannot undo it a period later (docs/safety.md): `ST`/`jR`
/// from anyone, `OF`, the workspace, IK divergence, the client watchdog, a following error,
/// and a stream's timeout (a network stall must not let delayed jog datagrams move the arm
/// again; a stream ended on purpose with a zero command ends without one). A mode change is
/// the holder's own request, and a joint-limit hold is no stop: they do not latch.
pub fn latches(cause: StopCause) -> bool {
    !matches!(cause, StopCause::ModeChange | StopCause::JointLimit)
}

/// How a stop in progress brings the arm to rest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Along {
    /// The running generator's path: its motion time is scaled down.
    Path,
    /// In joint space, from the velocity and acceleration at the start of the stop.
    Joints(JointStop),
}

/// A stop in progress.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stopping {
    /// Why.
    pub cause: StopCause,
    /// How.
    pub along: Along,
    /// The speed scale.
    pub brake: Brake,
}

/// Stops and the memory of the commanded velocity.
#[derive(Clone, Debug)]
pub struct Supervisor {
    /// The last commanded joint velocity (zero while nothing is commanded).
    velocity: Joints,
    /// The last commanded joint acceleration (the change of `velocity` over a period).
    acceleration: Joints,
    limits: StopLimits,
    /// Joint ranges.
    min: Joints,
    max: Joints,
    stopping: Option<Stopping>,
    /// The cause in force: the last stop's, until the next motion starts.
    cause: Option<StopCause>,
    /// The joint (0-based) a stream holds at its limit, or a following error stopped the arm for.
    held_joint: Option<u8>,
    /// The cause in force is a stream's hold: it ends with the hold.
    holding: bool,
    /// The stop that latched: streams stay refused until a motion starts on purpose.
    latch: Option<StopCause>,
}

impl Supervisor {
    /// The supervisor of a robot, at rest.
    pub fn new(config: &ValidRobot) -> Self {
        Self {
            velocity: Joints::zeros(config.dof()),
            acceleration: Joints::zeros(config.dof()),
            limits: StopLimits::new(config),
            min: config.per_joint(|j| j.min),
            max: config.per_joint(|j| j.max),
            stopping: None,
            cause: None,
            held_joint: None,
            holding: false,
            latch: None,
        }
    }

    /// Starts a stop (a stop already under way keeps its way and takes the new cause only if
    /// it has none of its own to report: the first cause is the one that matters).
    pub fn begin(&mut self, cause: StopCause, along: Along) {
        if self.stopping.is_none() {
            self.stopping = Some(Stopping {
                cause,
                along,
                brake: Brake::default(),
            });
            // A new stop: the joint a hold or an earlier stop named is no longer the point.
            self.held_joint = None;
        }
        self.cause = Some(self.stopping.as_ref().map_or(cause, |s| s.cause));
        self.holding = false;
        self.latch_for(cause);
    }

    /// A stop that found the arm at rest: nothing to brake, but its cause is in force and it
    /// latches as a stop in motion would (an `ST` between two streams stops the second).
    pub fn at_rest(&mut self, cause: StopCause) {
        if self.stopping.is_none() {
            self.cause = Some(cause);
            self.held_joint = None;
            self.holding = false;
        }
        self.latch_for(cause);
    }

    /// Latches `cause` if it is one that latches and none has yet.
    fn latch_for(&mut self, cause: StopCause) {
        if latches(cause) && self.latch.is_none() {
            self.latch = Some(cause);
        }
    }

    /// The stop that latched, if no motion has started on purpose since.
    pub fn latch(&self) -> Option<StopCause> {
        self.latch
    }

    /// A stop along the path that cannot follow it any more goes on in joint space, from the
    /// velocity commanded last.
    pub fn leave_path(&mut self) {
        let along = self.in_joint_space();
        if let Some(stop) = &mut self.stopping {
            stop.along = along;
            stop.brake = Brake::default();
        }
    }

    /// A stop in joint space from the commanded velocity and acceleration.
    pub fn in_joint_space(&self) -> Along {
        Along::Joints(JointStop::new(
            &self.velocity,
            &self.acceleration,
            &self.limits,
        ))
    }

    /// The next velocity of a stop in joint space, and its brake's scale (0: at rest); `None`
    /// if no such stop is under way.
    pub fn next_joint_velocity(&mut self) -> Option<(Joints, f64)> {
        let Some(Stopping {
            along: Along::Joints(stop),
            ..
        }) = &mut self.stopping
        else {
            return None;
        };
        Some(stop.next(&self.velocity, &self.acceleration, &self.limits))
    }

    /// The stop in progress, if any.
    pub fn stopping(&self) -> Option<&Stopping> {
        self.stopping.as_ref()
    }

    /// True while a stop is in progress.
    pub fn is_stopping(&self) -> bool {
        self.stopping.is_some()
    }

    /// The stop in progress, to advance its brake.
    pub fn stopping_mut(&mut self) -> Option<&mut Stopping> {
        self.stopping.as_mut()
    }

    /// The stop has brought the arm to rest.
    pub fn finish(&mut self) {
        self.stopping = None;
    }

    /// Clears the cause in force and the latch: a new motion starts on purpose.
    pub fn clear_cause(&mut self) {
        if self.stopping.is_none() {
            self.cause = None;
            self.held_joint = None;
            self.latch = None;
        }
    }

    /// Takes note of a stream's hold this tick (or none): the cause in force while it lasts.
    pub fn hold(&mut self, hold: Option<Hold>) {
        if self.stopping.is_some() || (hold.is_none() && !self.holding) {
            return;
        }
        (self.cause, self.held_joint) = match hold {
            Some(Hold::JointLimit(bound)) => {
                (Some(StopCause::JointLimit), bound.joint.checked_sub(1))
            }
            Some(Hold::Workspace | Hold::Contact(_)) => (Some(StopCause::Workspace), None),
            None => (None, None),
        };
        self.holding = hold.is_some();
    }

    /// Names the joint (0-based) the stop of `cause` is for (a following error's), if that
    /// is the cause in force. (A stop sets its cause in motion and at rest alike: `begin`,
    /// `at_rest`.)
    pub fn blame(&mut self, cause: StopCause, joint: u8) {
        if self.cause == Some(cause) {
            self.held_joint = Some(joint);
        }
    }

    /// The cause in force.
    pub fn cause(&self) -> Option<StopCause> {
        self.cause
    }

    /// The joint (0-based) a stream holds at its limit, or a following error stopped the arm for.
    pub fn held_joint(&self) -> Option<u8> {
        self.held_joint
    }

    /// Forgets the velocity and any stop: nothing is commanded (mode off, drives not taking
    /// set-points), so the next command starts from rest.
    pub fn reset(&mut self) {
        self.velocity.fill(0.0);
        self.acceleration.fill(0.0);
        self.stopping = None;
    }

    /// Takes note of the command sent this tick after `previous`.
    pub fn observe(&mut self, command: &Joints, previous: &Joints) {
        let period = self.limits.period;
        let memory = self.velocity.iter_mut().zip(self.acceleration.iter_mut());
        for ((v, a), (c, p)) in memory.zip(command.iter().zip(previous.iter())) {
            let next = (c - p) / period;
            *a = (next - *v) / period;
            *v = next;
        }
    }

    /// The last commanded joint velocity.
    pub fn velocity(&self) -> &Joints {
        &self.velocity
    }

    /// The last commanded joint acceleration.
    pub fn acceleration(&self) -> &Joints {
        &self.acceleration
    }

    /// Eases a joint-space stop's next velocity `v` (from the command `q`) where a joint
    /// decelerating by the common fraction would not stop before its limit: that joint brakes
    /// at its own acceleration limit instead, so the range clamp never has to stop it dead.
    /// The direction of motion gives way; in joint space there is no path to keep.
    pub fn keep_within_range(&self, q: &Joints, v: &mut Joints) {
        let t = self.limits.period;
        let limits = self.ranges();
        let state = q.iter().zip(self.velocity.iter());
        for ((v, (q, last)), ((lo, hi), a)) in v.iter_mut().zip(state).zip(limits) {
            let left = if *v > 0.0 { hi - q } else { q - lo } - libm::fabs(*v) * t;
            if *v * *v > 2.0 * a * left.max(0.0) {
                let slower = (libm::fabs(*last) - a * t).max(0.0);
                *v = libm::copysign(slower.min(libm::fabs(*v)), *v);
            }
        }
    }

    /// Each joint's range and acceleration limit.
    fn ranges(&self) -> impl Iterator<Item = ((&f64, &f64), &f64)> {
        let ranges = self.min.iter().zip(self.max.iter());
        ranges.zip(self.limits.a_max.iter())
    }

    /// True if every joint, stepping from `q` to `next` this tick, can still stop before its
    /// range at its acceleration limit: a set-point that could not would end on the range
    /// clamp, a dead stop.
    pub fn can_stop_within_range(&self, q: &Joints, next: &Joints) -> bool {
        let t = self.limits.period;
        let limits = self.ranges();
        q.iter()
            .zip(next.iter())
            .zip(limits)
            .all(|((q, n), ((lo, hi), a))| {
                let v = (n - q) / t;
                let left = if v > 0.0 { hi - n } else { n - lo };
                v * v <= 2.0 * a * left.max(0.0) + 1e-12
            })
    }

    /// The brake's budgets for a joint velocity `nominal` at scale 1 ([`StopLimits::budget`]).
    pub fn joint_budget(&self, nominal: &Joints) -> (f64, f64) {
        self.limits.budget(nominal)
    }
}
