//! Velocity streaming (`TW`, `jW`): a tool twist or joint rates, each valid for
//! [`TIMEOUT_PERIODS`] control periods, after which the arm ramps to rest.
//!
//! One tick, from the last joint command `q` and the streamed joint velocity `v`:
//!
//! 1. **target**: the command's joint rates, or zero once it is older than the timeout. A
//!    twist (base frame, or the tool frame turned into it) is scaled down to the Cartesian
//!    speed limits and turned into joint rates by a damped pseudo-inverse: the damping rises
//!    smoothly as the smallest singular value falls ([`damping`]) and acts along that
//!    direction only ([`pseudo_inverse`]), with the linear rows weighted
//!    ([`LINEAR_WEIGHT`]) so that the tool keeps its path and gives way in orientation; a
//!    7–8-joint arm adds a pull towards mid-range in the null space ([`null_space`]), and a
//!    correction back to the path the twist means ([`reference`]). The rates are scaled down
//!    to the joints' speed limits as a whole, so the tool keeps its direction and slows down
//!    rather than stops;
//! 2. **joint limits**: a joint heading for a limit may not be faster than it can still stop
//!    at a margin before it ([`joint_margin`]): twists scale the whole vector (the path stays),
//!    joint rates each joint;
//! 3. **acceleration**: `v` moves towards the target as far as every joint's acceleration
//!    limit allows, all joints by the same fraction ([`ramp`]); where the robot file limits
//!    jerk, the acceleration itself ramps up and down within those limits, so a stream starts,
//!    turns and comes to rest (at a workspace edge too) without an acceleration step;
//! 4. **workspace**: if the tool would end outside the workspace or in an exclusion box at
//!    the point where the arm could stop, it ramps to rest instead; a next set-point outside it
//!    is not commanded at all (the arm holds). An arm already outside moves freely, so that it
//!    can be driven out. The same for the whole arm ([`Body`]): a link that would come to rest
//!    in a box or another link it does not touch now ramps the stream to rest and holds it
//!    there until the command changes (`WN13 Held: L3 hits B1`, told once);
//! 5. **clearance**: before that, the speed falls as the body nears an obstacle: no faster
//!    than a gentle stop still ends within the gap less the margin, zero at the margin
//!    ([`clearance`]; the cap found in one tick holds for the next); within
//!    [`CONTACT`](super::body::CONTACT) of the margin where it would stop, the stream holds.
//!
//! The set-point is `q + v·T`. Each loop runs over the joints; no iteration is unbounded.

mod clearance;
mod damping;
mod joint_margin;
mod null_space;
mod pseudo_inverse;
mod ramp;
mod reference;

use clearance::speed_cap;
pub use damping::{MAX_DAMPING, SINGULAR_THRESHOLD};
use damping::{SingularDirection, singularity_damping};
pub use joint_margin::MARGIN_SHARE;

use armgate_protocol::client::{Hit, TwistFrame};

use super::body::Body;
use super::joint_stop::StopLimits;
use super::workspace::Workspace;
use crate::config::ValidRobot;
use crate::kinematics::{Chain, Joints};
use crate::math::{Frame, Twist};
use reference::PathReference;

/// A command holds for this many control periods; then the arm ramps to rest.
pub const TIMEOUT_PERIODS: u32 = 3;
/// Weight of the linear rows of the Jacobian and the twist (1/m) against the angular ones:
/// near a singularity the damped solution gives way where the weighted error is cheapest, so
/// with 10 a millimetre off the path costs as much as 0.57° of orientation, and a jog through
/// a wrist singularity keeps its straight line and lets the orientation wobble instead.
pub const LINEAR_WEIGHT: f64 = 10.0;

/// What a client streams.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StreamCommand {
    /// A tool twist `[vx, vy, vz, ωx, ωy, ωz]` (m/s, rad/s) in a frame.
    Twist(Twist, TwistFrame),
    /// Joint rates (rad/s, or m/s for prismatic joints), one per joint.
    JointRates(Joints),
}

impl StreamCommand {
    /// True if it asks for rest: every component zero (it re-arms a latched stream).
    pub fn is_zero(&self) -> bool {
        match self {
            Self::Twist(twist, _) => twist.iter().all(|v| *v == 0.0),
            Self::JointRates(rates) => rates.iter().all(|v| *v == 0.0),
        }
    }
}

/// What one streaming tick produced.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StreamStep {
    /// The joint set-point.
    pub q: Joints,
    /// The tool pose at `q` (computed for the workspace check; the controller reports it).
    pub pose: Frame,
    /// The stream has come to rest with no command left: the generators take over.
    pub finished: bool,
    /// The workspace made the arm slow down or hold.
    pub workspace_limit: bool,
    /// A joint held at the margin before its limit: its index, and whether the limit is its
    /// maximum.
    pub held_joint: Option<(usize, bool)>,
    /// Held before a link's contact: the link and what it would hit.
    pub contact: Option<Hit>,
}

/// The state of a velocity stream: the latest command, its age and the joint velocity.
#[derive(Clone, Debug)]
pub struct VelocityStream {
    command: Option<StreamCommand>,
    /// Ticks since the command arrived.
    age: u32,
    /// The joint velocity of the last set-point step.
    velocity: Joints,
    /// The change of `velocity` over the last period.
    acceleration: Joints,
    /// Speed limits: the lower of the joint generator's and the limiter's.
    max_speed: Joints,
    /// Acceleration limit × period: the largest velocity change per tick.
    max_change: Joints,
    /// Acceleration and jerk limits.
    limits: StopLimits,
    /// The joint limits with the margin kept.
    lower: Joints,
    upper: Joints,
    mid: Joints,
    cartesian_speed: [f64; 6],
    period: f64,
    /// The smallest singular direction, followed from tick to tick.
    singular: SingularDirection,
    /// Where a twist stream means the tool to be.
    reference: PathReference,
    /// The last tick's damping (0 away from singularities).
    damping: f64,
    /// The largest share of a joint's speed limit ([`speed_share`](Self::speed_share)) the
    /// next tick may ask for, near an obstacle ([`clearance`]); infinite away from any.
    clearance_cap: f64,
    /// Held before a link's contact: at rest until a different command arrives, so that the
    /// hold is told once.
    contact: Option<Hit>,
}

impl VelocityStream {
    /// An idle stream for a robot.
    pub fn new(config: &ValidRobot) -> Self {
        let period = config.control_period;
        let margin = |j: &crate::config::JointConfig| MARGIN_SHARE * (j.max - j.min);
        Self {
            command: None,
            age: 0,
            velocity: Joints::zeros(config.dof()),
            acceleration: Joints::zeros(config.dof()),
            max_speed: config.per_joint(|j| j.max_velocity.min(j.max_rate)),
            max_change: config.per_joint(|j| j.max_acceleration * period),
            limits: StopLimits::new(config),
            lower: config.per_joint(|j| j.min + margin(j)),
            upper: config.per_joint(|j| j.max - margin(j)),
            mid: config.per_joint(|j| 0.5 * (j.min + j.max)),
            cartesian_speed: config.cartesian.max_velocity,
            period,
            singular: SingularDirection::default(),
            reference: PathReference::default(),
            damping: 0.0,
            clearance_cap: f64::INFINITY,
            contact: None,
        }
    }

    /// Takes a new command (valid for [`TIMEOUT_PERIODS`] ticks from the next one). The caller
    /// has checked its numbers and, for joint rates, their count.
    pub fn command(&mut self, command: StreamCommand) {
        if self.command != Some(command) {
            self.contact = None;
        }
        self.command = Some(command);
        self.age = 0;
    }

    /// Drops the command: the arm ramps to rest within the acceleration limits.
    pub fn ramp_to_rest(&mut self) {
        self.command = None;
    }

    /// Ends the stream at once (mode change, drives not taking commands).
    pub fn halt(&mut self) {
        self.command = None;
        self.contact = None;
        self.clearance_cap = f64::INFINITY;
        self.velocity.iter_mut().for_each(|v| *v = 0.0);
        self.acceleration.iter_mut().for_each(|a| *a = 0.0);
    }

    /// Takes over an arm moving at `velocity` with `acceleration` (a stream resumed while it
    /// was being stopped).
    pub fn resume(&mut self, velocity: &Joints, acceleration: &Joints) {
        self.velocity = *velocity;
        self.acceleration = *acceleration;
    }

    /// True if the command is too old to hold on the next step: the client has gone quiet
    /// while asking for motion. A zero command running out is the stream's end on purpose:
    /// the step drops it and the arm ramps to rest as the zero asked.
    pub fn expires(&self) -> bool {
        self.age >= TIMEOUT_PERIODS && self.command.is_some_and(|c| !c.is_zero())
    }

    /// True while a command holds or the arm has not yet ramped to rest.
    pub fn is_active(&self) -> bool {
        self.command.is_some() || self.velocity.iter().any(|v| *v != 0.0)
    }

    /// The joint velocity of the last set-point step.
    pub fn velocity(&self) -> &Joints {
        &self.velocity
    }

    /// One tick from the last joint command `q` (checked by the chain).
    pub fn step(
        &mut self,
        chain: &Chain,
        (workspace, body): (&Workspace, &Body),
        q: &Joints,
    ) -> StreamStep {
        if self.age >= TIMEOUT_PERIODS {
            self.command = None;
        }
        self.age = self.age.saturating_add(1);
        let mut held_joint = None;
        // A twist's intended base-frame twist and the pose it starts from.
        let mut path = None;
        let target = match self.command {
            None => Joints::zeros(q.len()),
            Some(StreamCommand::JointRates(rates)) => {
                let mut target = rates;
                for (i, t) in target.iter_mut().enumerate() {
                    let cap = self.max_speed.get(i).copied().unwrap_or(0.0);
                    *t = crate::saturate::saturate(*t, -cap, cap);
                    let brake = self.braking_speed(q, i, *t);
                    if brake < libm::fabs(*t) {
                        if brake == 0.0 {
                            held_joint = Some((i, *t > 0.0));
                        }
                        *t = libm::copysign(brake, *t);
                    }
                }
                target
            }
            Some(StreamCommand::Twist(twist, frame)) => {
                let pose = tool_pose(chain, q);
                let intended = self.base_twist(&pose, &twist, frame);
                // Faded out where the damping gives way: it would only fight it there.
                let fade = 1.0 - self.damping / MAX_DAMPING;
                let correction =
                    self.reference
                        .correction(&pose, (twist, frame), &self.cartesian_speed)
                        * fade;
                path = Some((intended, pose));
                // The null space pulls only while the client asks for motion: a zero twist holds.
                let pull = intended.iter().any(|v| *v != 0.0);
                let rates = self.twist_rates(chain, q, &(intended + correction), pull);
                // The tightest joint, and whether it heads for its maximum.
                let (brake, tightest) = (0..rates.len())
                    .map(|i| {
                        let rate = rates.get(i).copied().unwrap_or(0.0);
                        let ratio = self.braking_speed(q, i, rate) / libm::fabs(rate);
                        (if ratio.is_nan() { 1.0 } else { ratio }, (i, rate > 0.0))
                    })
                    .fold((1.0, None), |(low, at), (ratio, joint)| {
                        if ratio < low {
                            (ratio, Some(joint))
                        } else {
                            (low, at)
                        }
                    });
                if brake == 0.0 {
                    held_joint = tightest;
                }
                scaled(&rates, brake)
            }
        };
        // Near an obstacle no faster than a stop still fits in the room left; held before a
        // contact, at rest until the command changes.
        let target = match self.contact {
            Some(_) => Joints::zeros(q.len()),
            None => scaled(
                &target,
                1.0 / (self.speed_share(&target) / self.clearance_cap).max(1.0),
            ),
        };
        let mut velocity = self.ramp(&target);
        // Checked only from inside: an arm already outside (after a recalibration, at start-up)
        // may be driven out, as joint moves may.
        let allowed = |q: &Joints| workspace.allows(&tool_pose(chain, q).translation.vector);
        let mut workspace_limit = false;
        let mut inside_now = None;
        let (rest, steady, braking) = self.resting_point(q, &velocity);
        // The whole arm too: a link that would come to rest in contact with something it
        // does not touch now holds the stream before it (issue 35), as the tool point does;
        // seen from the next set-point, as the tick's own check of the body sees it. The same
        // look ahead sets the next tick's speed cap.
        let (contact, gap_ahead) = body.ahead(chain, q, &advance(&rest, &velocity, self.period));
        self.contact = self.contact.or(contact);
        self.clearance_cap = body.clearance_at(q).map_or(f64::INFINITY, |gap| {
            let room = gap - body.envelope().margin();
            let times = (steady + self.period, braking);
            speed_cap(room, gap - gap_ahead, times, self.speed_share(&velocity))
        });
        let tool_blocked = !allowed(&rest) && *inside_now.get_or_insert(allowed(q));
        if tool_blocked || self.contact.is_some() {
            workspace_limit = tool_blocked;
            velocity = self.ramp(&Joints::zeros(q.len()));
        }
        let mut next = advance(q, &velocity, self.period);
        let mut pose = tool_pose(chain, &next);
        if !workspace.allows(&pose.translation.vector) && inside_now.unwrap_or_else(|| allowed(q)) {
            workspace_limit = true;
            velocity = Joints::zeros(q.len());
            next = *q;
            pose = tool_pose(chain, q);
        }
        match path {
            Some((intended, from)) => {
                self.reference.advance(&intended, &from, &pose, self.period);
            }
            None => self.reference.clear(),
        }
        let memory = self.acceleration.iter_mut().zip(self.velocity.iter_mut());
        for ((a, last), v) in memory.zip(velocity.iter()) {
            *a = (v - *last) / self.period;
            *last = *v;
        }
        StreamStep {
            q: next,
            pose,
            finished: !self.is_active(),
            workspace_limit,
            held_joint,
            contact: self.contact,
        }
    }

    /// A command's twist in the base frame (the tool frame turned by the tool's rotation at
    /// `pose`), within the Cartesian speed limits by one factor: the direction stays.
    fn base_twist(&self, pose: &Frame, twist: &Twist, frame: TwistFrame) -> Twist {
        let mut xi = *twist;
        if frame == TwistFrame::Tool {
            let linear = pose.rotation * xi.fixed_rows::<3>(0).into_owned();
            let angular = pose.rotation * xi.fixed_rows::<3>(3).into_owned();
            xi.fixed_rows_mut::<3>(0).copy_from(&linear);
            xi.fixed_rows_mut::<3>(3).copy_from(&angular);
        }
        self.within_cartesian_limits(xi)
    }

    /// `xi` scaled down by one factor to within the Cartesian speed limits (`TW`'s reply
    /// echoes it, so a client can say that and how a twist was cut). Out of line: the stream
    /// and the reply share one copy (flash).
    #[inline(never)]
    pub fn within_cartesian_limits(&self, xi: Twist) -> Twist {
        let over = xi
            .iter()
            .zip(self.cartesian_speed)
            .map(|(v, max)| libm::fabs(*v) / max)
            .fold(1.0, f64::max);
        xi / over
    }

    /// Joint rates for a base-frame twist at `q`, within the Cartesian and the joint speed
    /// limits; with `pull`, a 7–8-joint arm also moves towards mid-range in the null space.
    fn twist_rates(&mut self, chain: &Chain, q: &Joints, twist: &Twist, pull: bool) -> Joints {
        let mut xi = self.within_cartesian_limits(*twist);
        if xi.iter().all(|v| *v == 0.0) {
            return Joints::zeros(q.len());
        }
        let Ok(mut j) = chain.jacobian(q) else {
            return Joints::zeros(q.len());
        };
        // Weighted rows: the damping gives way in orientation before position.
        j.fixed_rows_mut::<3>(0).scale_mut(LINEAR_WEIGHT);
        xi.fixed_rows_mut::<3>(0).scale_mut(LINEAR_WEIGHT);
        let n = chain.dof();
        let outer = j * j.transpose();
        let damping = singularity_damping(&outer, n, &mut self.singular);
        self.damping = damping;
        let pull = if n > 6 && pull {
            null_space::mid_range_pull(q, &self.mid, &self.max_speed)
        } else {
            Joints::zeros(n)
        };
        let rates = pseudo_inverse::selectively_damped_rates(
            &j,
            &outer,
            n,
            &xi,
            damping,
            &self.singular,
            &pull,
        )
        .unwrap_or_else(|| Joints::zeros(q.len()));
        let over = self.speed_share(&rates).max(1.0);
        // A non-finite ratio means rates that are not numbers: no motion.
        if over.is_finite() {
            scaled(&rates, 1.0 / over)
        } else {
            Joints::zeros(q.len())
        }
    }

    /// The largest share of its speed limit a joint of `v` moves at.
    fn speed_share(&self, v: &Joints) -> f64 {
        v.iter()
            .zip(self.max_speed.iter())
            .map(|(v, max)| libm::fabs(*v) / max)
            .fold(0.0, f64::max)
    }

    /// The braking speed of joint `i` at `q` moving at `rate`.
    fn braking_speed(&self, q: &Joints, i: usize, rate: f64) -> f64 {
        let at = |v: &Joints| v.get(i).copied().unwrap_or(0.0);
        joint_margin::braking_speed(
            at(q),
            rate,
            (at(&self.lower), at(&self.upper)),
            at(&self.limits.a_max),
            self.period,
        )
    }

    /// One tick's velocity towards `target`: within the acceleration limits, and the jerk
    /// limits where the robot file sets them.
    fn ramp(&self, target: &Joints) -> Joints {
        if self.limits.j_max.is_some() {
            ramp::accelerate_within_jerk(&self.velocity, &self.acceleration, target, &self.limits)
        } else {
            ramp::accelerate(&self.velocity, target, &self.max_change)
        }
    }

    /// Where the arm would come to rest if it braked from `velocity` after this tick: about
    /// `q + v·(T + t_stop/2)`. With jerk limits the acceleration must first ramp out and the
    /// brake ramps in and out: `v` grows by the step's acceleration over the longest ramp to
    /// full acceleration, and the time by two such ramps. With the time it moves on at speed
    /// (`T` and the ramps) and `t_stop/2`, for the clearance cap.
    fn resting_point(&self, q: &Joints, velocity: &Joints) -> (Joints, f64, f64) {
        let a_max = &self.limits.a_max;
        let ramp = self.limits.j_max.map_or(0.0, |j_max| {
            let ramps = a_max.iter().zip(j_max.iter()).map(|(a, j)| a / j);
            ramps.fold(0.0, f64::max)
        });
        let mut v = *velocity;
        if ramp > 0.0 {
            for (v, last) in v.iter_mut().zip(self.velocity.iter()) {
                *v += (*v - last) / self.period * ramp;
            }
        }
        let stop_time = v
            .iter()
            .zip(a_max.iter())
            .map(|(v, a)| libm::fabs(*v) / a)
            .fold(0.0, f64::max);
        let (steady, braking) = (self.period + 2.0 * ramp, 0.5 * stop_time);
        (advance(q, &v, steady + braking), steady, braking)
    }
}

/// The tool pose at `q` (finite: the last command, or a step from it by a finite velocity),
/// through one out-of-line copy of the chain's walk, which is `inline(always)` for the IK:
/// the stream's four calls would otherwise each carry their own (tens of KiB of flash).
#[inline(never)]
fn tool_pose(chain: &Chain, q: &Joints) -> Frame {
    chain.pose(q)
}

/// `q + v·t`.
fn advance(q: &Joints, v: &Joints, t: f64) -> Joints {
    let mut out = *q;
    for (o, v) in out.iter_mut().zip(v.iter()) {
        *o += v * t;
    }
    out
}

/// `v · factor`.
fn scaled(v: &Joints, factor: f64) -> Joints {
    let mut out = *v;
    out.iter_mut().for_each(|x| *x *= factor);
    out
}
