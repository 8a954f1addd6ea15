//! The Cartesian trajectory generator (spec §4.2) and the shape sources in its place (§4.5).

use super::Refusal;
use super::blend::{
    self, Axes, Blended, LegChain, acceleration_budget, blend_start, jerk_budget, jerk_towards,
};
use super::shape::Shape;
use super::straight_line::StraightLine;
use crate::math::{self, Frame, Rotation3, Vector3};

/// Rest-to-rest Cartesian moves: the tool origin moves along the straight segment to the goal,
/// the orientation turns about the fixed axis of the relative rotation, both synchronised to
/// finish together. Also runs a [`Shape`] instead of a move. Starts from its own set-point (the
/// commanded pose), so starting never jumps.
#[derive(Clone, Debug)]
pub struct CartesianGenerator {
    setpoint: Frame,
    limits: Limits,
    motion: Option<Motion>,
}

/// Per-component limits (x, y, z, rx, ry, rz): velocity, acceleration, and jerk if the
/// profiles are jerk-limited (the seed's trapezoids if not).
#[derive(Clone, Copy, Debug)]
struct Limits {
    v: [f64; 6],
    a: [f64; 6],
    j: Option<[f64; 6]>,
}

/// One straight Cartesian leg: the tool origin along the segment, the orientation about the
/// fixed axis of the relative rotation, both stretched to the leg's duration.
#[derive(Clone, Copy, Debug)]
struct Leg {
    start: Frame,
    goal: Frame,
    translation: StraightLine,
    /// A path from the zero rotation vector to the relative rotation's vector.
    rotation: StraightLine,
    duration: f64,
}

impl blend::Leg for Leg {
    fn duration(&self) -> f64 {
        self.duration
    }
}

impl Leg {
    /// The minimum-time leg from `start` to `goal` lasting at least `min_duration`, within the
    /// per-component limits (jerk-limited if `j_max` is given). Refused (jerk-limited) if the
    /// move's times would overflow.
    fn plan(
        start: Frame,
        goal: Frame,
        min_duration: f64,
        limits: &Limits,
    ) -> Result<Self, Refusal> {
        let delta = math::diff(&start, &goal);
        let ([vl @ .., _, _, _], [_, _, _, va @ ..]) = (limits.v, limits.v);
        let ([al @ .., _, _, _], [_, _, _, aa @ ..]) = (limits.a, limits.a);
        let (jl, ja) = limits
            .j
            .map(|[x, y, z, rx, ry, rz]| ([x, y, z], [rx, ry, rz]))
            .unzip();
        let plan = |from: &[f64], to: &[f64], v: &[f64], a: &[f64], j: Option<[f64; 3]>| {
            StraightLine::plan_with(from, to, v, a, j.as_ref().map(|j| j.as_slice()))
                .map_err(|_| Refusal::InvalidNumber)
        };
        let (from, to): ([f64; 3], [f64; 3]) = (
            start.translation.vector.into(),
            goal.translation.vector.into(),
        );
        let translation = plan(&from, &to, &vl, &al, jl)?;
        let [_, _, _, angular @ ..]: [f64; 6] = delta.into();
        let rotation = plan(&[0.0; 3], &angular, &va, &aa, ja)?;
        let duration = translation
            .duration()
            .max(rotation.duration())
            .max(min_duration);
        Ok(Self {
            start,
            goal,
            translation: translation.stretched(duration),
            rotation: rotation.stretched(duration),
            duration,
        })
    }

    /// [`plan`](Self::plan) for a leg whose end blends into a leg to `then`: jerk-limited, its
    /// jerk is halved on the components both move along ([`jerk_towards`]).
    fn plan_towards(
        start: Frame,
        goal: Frame,
        min_duration: f64,
        limits: &Limits,
        then: Option<Frame>,
    ) -> Result<Self, Refusal> {
        let leg = Self::plan(start, goal, min_duration, limits)?;
        let (Some(j_max), Some(then)) = (limits.j, then) else {
            return Ok(leg);
        };
        let next = Self::plan(goal, then, 0.0, limits)?;
        let ([jl @ .., _, _, _], [_, _, _, ja @ ..]) = (j_max, j_max);
        let (mut linear, mut angular) = ([0.0; 3], [0.0; 3]);
        let (own, after) = (&leg.translation, &next.translation);
        jerk_towards(&jl, own.direction(), after.direction(), &mut linear);
        let (own, after) = (&leg.rotation, &next.rotation);
        jerk_towards(&ja, own.direction(), after.direction(), &mut angular);
        let ([l0, l1, l2], [r0, r1, r2]) = (linear, angular);
        let halved = Limits {
            j: Some([l0, l1, l2, r0, r1, r2]),
            ..*limits
        };
        Self::plan(start, goal, min_duration, &halved)
    }

    /// The pose at leg time `t` (the goal from the end on).
    fn pose(&self, t: f64) -> Frame {
        if t >= self.duration {
            return self.goal;
        }
        let mut p = [0.0; 3];
        let mut r = [0.0; 3];
        self.translation.point(t, &mut p);
        self.rotation.point(t, &mut r);
        let turn = Rotation3::new(Vector3::from(r));
        Frame::from_parts(Vector3::from(p).into(), turn * self.start.rotation)
    }

    fn is_stuck(&self) -> bool {
        self.translation.is_stuck() || self.rotation.is_stuck()
    }
}

// Unboxed on purpose: no heap, and only one motion exists at a time.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug)]
enum Motion {
    /// Straight legs, blended into one another (one leg unless a sequence blends).
    Move(LegChain<Leg>),
    Shape {
        shape: Shape,
        start: Frame,
        elapsed: f64,
        /// Set by [`CartesianGenerator::finish_shape`].
        end_time: Option<f64>,
    },
}

impl Motion {
    fn elapsed(&self) -> f64 {
        match self {
            Self::Move(chain) => chain.elapsed(),
            Self::Shape { elapsed, .. } => *elapsed,
        }
    }

    /// The set-point at motion time `t`, and whether the motion has ended by then.
    fn sample(&self, t: f64) -> (Frame, bool) {
        match *self {
            Self::Move(ref chain) => {
                if chain.ended_at(t) {
                    return (chain.leg().goal, true);
                }
                let Blended {
                    lead: (leg, t_lead),
                    residual,
                } = chain.at(t);
                let mut pose = leg.pose(t_lead);
                if let Some((tail, t_tail)) = residual {
                    // The way the finishing leg still has to go, added on.
                    let rest = tail.pose(t_tail);
                    pose.translation.vector +=
                        rest.translation.vector - tail.goal.translation.vector;
                    pose.rotation = rest.rotation * tail.goal.rotation.inverse() * pose.rotation;
                }
                (pose, false)
            }
            Self::Shape {
                shape,
                start,
                end_time,
                ..
            } => {
                if end_time.is_some_and(|end| t >= end) {
                    return (start, true);
                }
                let mut pose = start;
                pose.translation.vector += shape.offset(t);
                (pose, false)
            }
        }
    }
}

impl CartesianGenerator {
    /// A generator holding `hold`, with per-component limits (x, y, z, rx, ry, rz).
    pub fn new(hold: Frame, v_max: [f64; 6], a_max: [f64; 6]) -> Self {
        Self {
            setpoint: hold,
            limits: Limits {
                v: v_max,
                a: a_max,
                j: None,
            },
            motion: None,
        }
    }

    /// This generator planning jerk-limited (double-S) moves within per-component jerk limits
    /// (x, y, z, rx, ry, rz); `None`: the seed's trapezoids.
    pub fn with_jerk_limits(self, j_max: Option<[f64; 6]>) -> Self {
        Self {
            limits: Limits {
                j: j_max,
                ..self.limits
            },
            ..self
        }
    }

    /// Aborts any motion and holds `pose` ("hold here").
    pub fn hold(&mut self, pose: Frame) {
        self.setpoint = pose;
        self.motion = None;
    }

    /// Starts a move to `goal` lasting at least `min_duration` s from the current set-point;
    /// returns the planned duration. Refused while moving, or (jerk-limited) if the move's times
    /// would overflow.
    pub fn move_to(&mut self, goal: Frame, min_duration: f64) -> Result<f64, Refusal> {
        self.move_towards(goal, min_duration, None)
    }

    /// [`move_to`](Self::move_to) for a sequence leg whose end will blend into a leg to `then`:
    /// with jerk-limited profiles its jerk is halved on the components both legs move along,
    /// leaving the other half to the next leg ([`blend_into`](Self::blend_into)).
    pub fn move_towards(
        &mut self,
        goal: Frame,
        min_duration: f64,
        then: Option<Frame>,
    ) -> Result<f64, Refusal> {
        if self.motion.is_some() {
            return Err(Refusal::Busy);
        }
        let leg = Leg::plan_towards(self.setpoint, goal, min_duration, &self.limits, then)?;
        self.motion = Some(Motion::Move(LegChain::new(leg)));
        Ok(leg.duration)
    }

    /// Queues a move to `goal` (at least `min_duration` s) that starts before the running move
    /// ends and blends with it, passing its goal within `tolerance` (m + rad, the via-point
    /// metric) without stopping (see `blend.rs`). `then`: the pose after `goal` if the move
    /// blends into a move there too (see [`move_towards`](Self::move_towards)). `Ok(false)`,
    /// nothing queued, if the blend would not save time or would overlap for less than
    /// `min_overlap` (the control period): the caller stops at the goal instead. Refused unless
    /// a move runs with nothing queued.
    pub fn blend_into(
        &mut self,
        goal: Frame,
        min_duration: f64,
        tolerance: f64,
        then: Option<Frame>,
        min_overlap: f64,
    ) -> Result<bool, Refusal> {
        let limits = self.limits;
        let Some(Motion::Move(chain)) = &mut self.motion else {
            return Err(Refusal::NoGoal);
        };
        if !chain.accepts_next() {
            return Err(Refusal::Busy);
        }
        let current = *chain.leg();
        let full = Leg::plan_towards(current.goal, goal, min_duration, &limits, then)?;
        // What the running leg leaves of the limits, translation and rotation apart.
        let shared = |limit: &[f64; 6], share: fn(&StraightLine, &[f64], &[f64], &mut [f64])| {
            let ([l @ .., _, _, _], [_, _, _, r @ ..]) = (*limit, *limit);
            let (mut linear, mut angular) = ([0.0; 3], [0.0; 3]);
            share(
                &current.translation,
                full.translation.direction(),
                &l,
                &mut linear,
            );
            share(
                &current.rotation,
                full.rotation.direction(),
                &r,
                &mut angular,
            );
            let ([l0, l1, l2], [r0, r1, r2]) = (linear, angular);
            [l0, l1, l2, r0, r1, r2]
        };
        let budget = Limits {
            a: shared(&limits.a, acceleration_budget),
            j: limits.j.map(|j| shared(&j, jerk_budget)),
            ..limits
        };
        let budgeted = Leg::plan_towards(current.goal, goal, min_duration, &budget, then)
            .ok()
            .filter(|next| !next.is_stuck())
            .map(|next| {
                let ([vl @ .., _, _, _], [_, _, _, va @ ..]) = (limits.v, limits.v);
                let axes = [
                    Axes {
                        current: &current.translation,
                        next: &next.translation,
                        v_max: &vl,
                    },
                    Axes {
                        current: &current.rotation,
                        next: &next.rotation,
                        v_max: &va,
                    },
                ];
                let start = blend_start(
                    &axes,
                    current.duration,
                    next.duration,
                    tolerance,
                    chain.elapsed(),
                );
                (next, start)
            });
        chain.queue_if_worthwhile(&full, budgeted, min_overlap)
    }

    /// True if a move runs that a next one may be blended into ([`blend_into`](Self::blend_into)).
    pub fn accepts_blend(&self) -> bool {
        matches!(&self.motion, Some(Motion::Move(chain)) if chain.accepts_next())
    }

    /// Starts `shape` at the current set-point. Refused while moving.
    pub fn start_shape(&mut self, shape: Shape) -> Result<(), Refusal> {
        shape.validate()?;
        if self.motion.is_some() {
            return Err(Refusal::Busy);
        }
        self.motion = Some(Motion::Shape {
            shape,
            start: self.setpoint,
            elapsed: 0.0,
            end_time: None,
        });
        Ok(())
    }

    /// Asks a running shape to stop where it started, at the end of the current revolution
    /// (circle) or the next centre crossing (sinusoid). Returns false if no shape runs.
    pub fn finish_shape(&mut self) -> bool {
        match &mut self.motion {
            Some(Motion::Shape {
                shape,
                elapsed,
                end_time,
                ..
            }) => {
                *end_time = Some(shape.end_time(*elapsed));
                true
            }
            _ => false,
        }
    }

    /// Motion time left (s) until a motion that ends at speed stops: a shape asked to finish
    /// ends at its start point with its velocity, so the controller slows its time down before
    /// then. `None` for moves (they end at rest) and for shapes not asked to finish.
    pub fn time_to_abrupt_end(&self) -> Option<f64> {
        match &self.motion {
            Some(Motion::Shape {
                elapsed,
                end_time: Some(end),
                ..
            }) => Some((end - elapsed).max(0.0)),
            _ => None,
        }
    }

    /// True while a shape runs (its path was not checked before it started).
    pub fn runs_shape(&self) -> bool {
        matches!(self.motion, Some(Motion::Shape { .. }))
    }

    /// Motion time reached so far (s); 0 when idle.
    pub fn elapsed(&self) -> f64 {
        self.motion.as_ref().map_or(0.0, Motion::elapsed)
    }

    /// The set-point the motion would have at motion time `t`, without advancing, and whether
    /// the motion ends there (then the set-point is exactly its goal, or the shape's start
    /// point); the held set-point when idle.
    pub fn sample(&self, t: f64) -> (Frame, bool) {
        self.motion
            .as_ref()
            .map_or((self.setpoint, false), |m| m.sample(t))
    }

    /// Advances the motion to motion time `t`, given `sample = self.sample(t)` (computed once by
    /// a caller that first checks the set-point); an ended motion holds its last set-point.
    pub fn commit(&mut self, t: f64, (setpoint, ended): (Frame, bool)) {
        let Some(motion) = &mut self.motion else {
            return;
        };
        match motion {
            Motion::Move(chain) => chain.commit(t),
            Motion::Shape { elapsed, .. } => *elapsed = t,
        }
        if ended {
            self.hold(setpoint);
        } else {
            self.setpoint = setpoint;
        }
    }

    /// Advances the motion to motion time `t` and returns the set-point and whether the motion
    /// ended ([`sample`](Self::sample), then [`commit`](Self::commit)).
    pub fn advance_to(&mut self, t: f64) -> (Frame, bool) {
        let sample = self.sample(t);
        self.commit(t, sample);
        sample
    }

    /// True while a move or shape is in progress.
    pub fn is_moving(&self) -> bool {
        self.motion.is_some()
    }

    /// The current set-point.
    pub fn setpoint(&self) -> Frame {
        self.setpoint
    }
}
