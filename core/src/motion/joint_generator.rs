//! The joint-space trajectory generator (spec §4.3).

use super::Refusal;
use super::blend::{
    self, Axes, Blended, LegChain, acceleration_budget, blend_start, jerk_budget, jerk_towards,
};
use super::straight_line::StraightLine;
use crate::MAX_JOINTS;
use crate::kinematics::Joints;

/// Rest-to-rest joint moves along a straight line in joint space, synchronised so that all
/// joints finish together. Starts from its own set-point (the commanded state), so starting a
/// move never jumps. A via-point sequence may blend the next move into the running one
/// ([`blend_into`](Self::blend_into)).
#[derive(Clone, Debug)]
pub struct JointGenerator {
    setpoint: Joints,
    v_max: Joints,
    a_max: Joints,
    /// Jerk limits: jerk-limited profiles if set, the seed's trapezoids if not.
    j_max: Option<Joints>,
    motion: Option<LegChain<Leg>>,
}

/// One straight move in joint space.
#[derive(Clone, Copy, Debug)]
struct Leg {
    line: StraightLine,
    goal: Joints,
    /// Can exceed the line's duration: a zero-length move still lasts `min_duration`.
    duration: f64,
}

impl blend::Leg for Leg {
    fn duration(&self) -> f64 {
        self.duration
    }
}

impl Leg {
    /// Refused (jerk-limited) if the move's times would overflow.
    fn plan(
        start: &Joints,
        goal: Joints,
        min_duration: f64,
        limits: (&[f64], &[f64], Option<&[f64]>),
    ) -> Result<Self, Refusal> {
        let (v_max, a_max, j_max) = limits;
        let line = StraightLine::plan_with(start, &goal, v_max, a_max, j_max)
            .map_err(|_| Refusal::InvalidNumber)?;
        let duration = line.duration().max(min_duration);
        Ok(Self {
            line: line.stretched(duration),
            goal,
            duration,
        })
    }

    /// [`plan`](Self::plan) for a leg whose end blends into a leg to `then`: jerk-limited, its
    /// jerk is halved on the joints both move ([`jerk_towards`]).
    fn plan_towards(
        start: &Joints,
        goal: Joints,
        min_duration: f64,
        limits: (&[f64], &[f64], Option<&[f64]>),
        then: Option<Joints>,
    ) -> Result<Self, Refusal> {
        let leg = Self::plan(start, goal, min_duration, limits)?;
        let (v_max, a_max, j_max) = limits;
        let (Some(j_max), Some(then)) = (j_max, then) else {
            return Ok(leg);
        };
        let next = StraightLine::plan(&goal, &then, v_max, a_max);
        let mut halved = [0.0; MAX_JOINTS];
        jerk_towards(j_max, leg.line.direction(), next.direction(), &mut halved);
        let halved = halved.get(..j_max.len()).unwrap_or(j_max);
        Self::plan(start, goal, min_duration, (v_max, a_max, Some(halved)))
    }

    /// The joints at leg time `t` (the goal from the end on), written to `out`.
    fn point(&self, t: f64, out: &mut Joints) {
        if t >= self.duration {
            *out = self.goal;
        } else {
            self.line.point(t, out);
        }
    }
}

impl JointGenerator {
    /// A generator holding `hold`, with per-joint velocity and acceleration limits.
    pub fn new(hold: Joints, v_max: Joints, a_max: Joints) -> Self {
        Self {
            setpoint: hold,
            v_max,
            a_max,
            j_max: None,
            motion: None,
        }
    }

    /// This generator planning jerk-limited (double-S) moves within per-joint jerk limits;
    /// `None`: the seed's trapezoids.
    pub fn with_jerk_limits(self, j_max: Option<Joints>) -> Self {
        Self { j_max, ..self }
    }

    /// Aborts any motion and holds `q` ("hold here").
    pub fn hold(&mut self, q: Joints) {
        self.setpoint = q;
        self.motion = None;
    }

    /// Starts a move to `goal` lasting at least `min_duration` seconds from the current
    /// set-point; returns the planned duration. Refused while moving, or (jerk-limited) if the
    /// move's times would overflow.
    pub fn move_to(&mut self, goal: Joints, min_duration: f64) -> Result<f64, Refusal> {
        self.move_towards(goal, min_duration, None)
    }

    /// [`move_to`](Self::move_to) for a sequence leg whose end will blend into a leg to `then`:
    /// with jerk-limited profiles its jerk is halved on the joints both legs move, leaving the
    /// other half to the next leg ([`blend_into`](Self::blend_into)).
    pub fn move_towards(
        &mut self,
        goal: Joints,
        min_duration: f64,
        then: Option<Joints>,
    ) -> Result<f64, Refusal> {
        if self.motion.is_some() {
            return Err(Refusal::Busy);
        }
        let limits = (&self.v_max[..], &self.a_max[..], self.j_max.as_deref());
        let leg = Leg::plan_towards(&self.setpoint, goal, min_duration, limits, then)?;
        self.motion = Some(LegChain::new(leg));
        Ok(leg.duration)
    }

    /// Queues a move to `goal` (at least `min_duration` s) that starts before the running move
    /// ends and blends with it, passing its goal within `tolerance` (Euclidean, rad or m)
    /// without stopping (see `blend.rs`). `then`: the point after `goal` if the move blends
    /// into a move there too (see [`move_towards`](Self::move_towards)). `Ok(false)`, nothing
    /// queued, if the blend would not save time or would overlap for less than `min_overlap`
    /// (the control period): the caller stops at the goal instead. Refused unless a move runs
    /// with nothing queued.
    pub fn blend_into(
        &mut self,
        goal: Joints,
        min_duration: f64,
        tolerance: f64,
        then: Option<Joints>,
        min_overlap: f64,
    ) -> Result<bool, Refusal> {
        let Some(chain) = &mut self.motion else {
            return Err(Refusal::NoGoal);
        };
        if !chain.accepts_next() {
            return Err(Refusal::Busy);
        }
        let current = *chain.leg();
        let limits = (&self.v_max[..], &self.a_max[..], self.j_max.as_deref());
        let full = Leg::plan_towards(&current.goal, goal, min_duration, limits, then)?;
        // What the running leg leaves of the limits.
        let direction = full.line.direction();
        let mut a_budget = self.a_max;
        acceleration_budget(&current.line, direction, &self.a_max, &mut a_budget);
        let j_budget = self.j_max.map(|j_max| {
            let mut budget = j_max;
            jerk_budget(&current.line, direction, &j_max, &mut budget);
            budget
        });
        let budget = (&self.v_max[..], &a_budget[..], j_budget.as_deref());
        let budgeted = Leg::plan_towards(&current.goal, goal, min_duration, budget, then)
            .ok()
            .filter(|next| !next.line.is_stuck())
            .map(|next| {
                let axes = [Axes {
                    current: &current.line,
                    next: &next.line,
                    v_max: &self.v_max,
                }];
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
        self.motion.as_ref().is_some_and(LegChain::accepts_next)
    }

    /// Advances the motion by `dt` seconds and returns the set-point. At the end of a move the
    /// set-point is exactly the goal and the generator holds it; the flag is true on that tick.
    pub fn advance(&mut self, dt: f64) -> (Joints, bool) {
        let Some(chain) = &mut self.motion else {
            return (self.setpoint, false);
        };
        let t = chain.elapsed() + dt;
        if chain.ended_at(t) {
            let goal = chain.leg().goal;
            self.hold(goal);
            return (self.setpoint, true);
        }
        let Blended {
            lead: (leg, t_lead),
            residual,
        } = chain.at(t);
        leg.point(t_lead, &mut self.setpoint);
        if let Some((tail, t_tail)) = residual {
            // The way the finishing move still has to go, added on.
            let mut rest = tail.goal;
            tail.point(t_tail, &mut rest);
            for ((q, r), g) in self
                .setpoint
                .iter_mut()
                .zip(rest.iter())
                .zip(tail.goal.iter())
            {
                *q += r - g;
            }
        }
        chain.commit(t);
        (self.setpoint, false)
    }

    /// Where the motion ends if it runs along one straight line from the set-point: a single
    /// leg's goal, or the set-point itself while holding; `None` while two legs blend (or
    /// one is queued to), whose way bends. A stop along the motion's path never passes it.
    pub fn straight_end(&self) -> Option<Joints> {
        match &self.motion {
            None => Some(self.setpoint),
            Some(chain) => chain.is_alone().then_some(chain.leg().goal),
        }
    }

    /// True while a move is in progress.
    pub fn is_moving(&self) -> bool {
        self.motion.is_some()
    }

    /// The current set-point.
    pub fn setpoint(&self) -> Joints {
        self.setpoint
    }
}
