//! The Cartesian trajectory generator (spec §4.2) and the shape sources in its place (§4.5).

use super::Refusal;
use super::shape::Shape;
use super::straight_line::StraightLine;
use crate::math::{Frame, Rotation, Vec3};

/// Rest-to-rest Cartesian moves: the tool origin moves along the straight segment to the goal,
/// the orientation turns about the fixed axis of the relative rotation, both synchronised to
/// finish together. Also runs a [`Shape`] instead of a move. Starts from its own set-point (the
/// commanded pose), so starting never jumps.
#[derive(Clone, Debug)]
pub struct CartesianGenerator {
    setpoint: Frame,
    /// x, y, z then rx, ry, rz.
    v_max: [f64; 6],
    a_max: [f64; 6],
    motion: Option<Motion>,
}

// Unboxed on purpose: no heap, and only one motion exists at a time.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug)]
enum Motion {
    Move {
        start: Frame,
        goal: Frame,
        translation: StraightLine,
        /// A path from the zero rotation vector to the relative rotation's vector.
        rotation: StraightLine,
        start_time: f64,
        duration: f64,
    },
    Shape {
        shape: Shape,
        start: Frame,
        start_time: f64,
        /// Set by [`CartesianGenerator::finish_shape`].
        end_time: Option<f64>,
    },
}

impl CartesianGenerator {
    /// A generator holding `hold`, with per-component limits (x, y, z, rx, ry, rz).
    pub fn new(hold: Frame, v_max: [f64; 6], a_max: [f64; 6]) -> Self {
        Self {
            setpoint: hold,
            v_max,
            a_max,
            motion: None,
        }
    }

    /// Aborts any motion and holds `pose` ("hold here").
    pub fn hold(&mut self, pose: Frame) {
        self.setpoint = pose;
        self.motion = None;
    }

    /// Starts a move to `goal` lasting at least `min_duration` s from the current set-point at
    /// time `now`; returns the planned duration. Refused while moving.
    pub fn move_to(&mut self, goal: Frame, min_duration: f64, now: f64) -> Result<f64, Refusal> {
        if self.motion.is_some() {
            return Err(Refusal::Busy);
        }
        let start = self.setpoint;
        let delta = start.diff(&goal);
        let [vl @ .., _, _, _] = self.v_max;
        let [al @ .., _, _, _] = self.a_max;
        let [_, _, _, va @ ..] = self.v_max;
        let [_, _, _, aa @ ..] = self.a_max;
        let translation = StraightLine::plan(&start.pos.to_array(), &goal.pos.to_array(), &vl, &al);
        let rotation = StraightLine::plan(&[0.0; 3], &delta.angular.to_array(), &va, &aa);
        let duration = translation
            .duration()
            .max(rotation.duration())
            .max(min_duration);
        self.motion = Some(Motion::Move {
            start,
            goal,
            translation: translation.stretched(duration),
            rotation: rotation.stretched(duration),
            start_time: now,
            duration,
        });
        Ok(duration)
    }

    /// Starts `shape` at the current set-point at time `now`. Refused while moving.
    pub fn start_shape(&mut self, shape: Shape, now: f64) -> Result<(), Refusal> {
        shape.validate()?;
        if self.motion.is_some() {
            return Err(Refusal::Busy);
        }
        self.motion = Some(Motion::Shape {
            shape,
            start: self.setpoint,
            start_time: now,
            end_time: None,
        });
        Ok(())
    }

    /// Asks a running shape to stop where it started, at the end of the current revolution
    /// (circle) or the next centre crossing (sinusoid). Returns false if no shape runs.
    pub fn finish_shape(&mut self, now: f64) -> bool {
        match &mut self.motion {
            Some(Motion::Shape {
                shape,
                start_time,
                end_time,
                ..
            }) => {
                *end_time = Some(*start_time + shape.end_time(now - *start_time));
                true
            }
            _ => false,
        }
    }

    /// Advances to time `now` and returns the set-point and whether a motion ended this tick
    /// (then the set-point is exactly its goal, or the shape's start point).
    pub fn update(&mut self, now: f64) -> (Frame, bool) {
        match self.motion {
            None => return (self.setpoint, false),
            Some(Motion::Move {
                start,
                goal,
                translation,
                rotation,
                start_time,
                duration,
            }) => {
                let t = now - start_time;
                if t >= duration {
                    self.hold(goal);
                    return (goal, true);
                }
                let mut p = [0.0; 3];
                let mut r = [0.0; 3];
                translation.point(t, &mut p);
                rotation.point(t, &mut r);
                let turn = Rotation::from_rotation_vector(Vec3::from_array(r));
                self.setpoint = Frame::new(turn * start.rot, Vec3::from_array(p));
            }
            Some(Motion::Shape {
                shape,
                start,
                start_time,
                end_time,
            }) => {
                if end_time.is_some_and(|end| now >= end) {
                    self.hold(start);
                    return (start, true);
                }
                self.setpoint = Frame::new(start.rot, start.pos + shape.offset(now - start_time));
            }
        }
        (self.setpoint, false)
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
