//! The joint-space trajectory generator (spec §4.3).

use super::Refusal;
use super::straight_line::StraightLine;
use crate::kinematics::Joints;

/// Rest-to-rest joint moves along a straight line in joint space, synchronised so that all
/// joints finish together. Starts from its own set-point (the commanded state), so starting a
/// move never jumps.
#[derive(Clone, Debug)]
pub struct JointGenerator {
    setpoint: Joints,
    v_max: Joints,
    a_max: Joints,
    /// Jerk limits: jerk-limited profiles if set, the seed's trapezoids if not.
    j_max: Option<Joints>,
    motion: Option<Motion>,
}

#[derive(Clone, Copy, Debug)]
struct Motion {
    line: StraightLine,
    goal: Joints,
    /// Motion time reached so far (s).
    elapsed: f64,
    /// Can exceed the line's duration: a zero-length move still lasts `min_duration`.
    duration: f64,
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
        if self.motion.is_some() {
            return Err(Refusal::Busy);
        }
        let line = StraightLine::plan_with(
            &self.setpoint,
            &goal,
            &self.v_max,
            &self.a_max,
            self.j_max.as_deref(),
        )
        .map_err(|_| Refusal::InvalidNumber)?;
        let duration = line.duration().max(min_duration);
        self.motion = Some(Motion {
            line: line.stretched(duration),
            goal,
            elapsed: 0.0,
            duration,
        });
        Ok(duration)
    }

    /// Advances the motion by `dt` seconds and returns the set-point. At the end of a move the
    /// set-point is exactly the goal and the generator holds it; the flag is true on that tick.
    pub fn advance(&mut self, dt: f64) -> (Joints, bool) {
        let Some(m) = &mut self.motion else {
            return (self.setpoint, false);
        };
        m.elapsed += dt;
        if m.elapsed >= m.duration {
            let goal = m.goal;
            self.hold(goal);
            return (self.setpoint, true);
        }
        m.line.point(m.elapsed, &mut self.setpoint);
        (self.setpoint, false)
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
