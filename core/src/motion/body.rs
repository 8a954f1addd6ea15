//! The whole arm inside the envelope: its body ([`Envelope`], capsules on every link) kept out
//! of the exclusion boxes, inside the bounds and clear of itself (docs/safety.md, "The whole
//! arm inside the envelope").
//!
//! * **Before a joint move starts** ([`Body::check_path`]) its whole straight way in joint
//!   space is checked piece by piece, every capsule grown by what it can sweep over half a
//!   piece (a bound from the joint steps and each link's reach from every axis), so no
//!   contact between the checked poses is missed: `ER25 Cmd jB L3 hits B1 at 40%`.
//! * **Every tick** ([`Body::check_tick`]) the commanded pose and the pose where a stop begun
//!   now would end are checked; a new hit stops the motion (`ER21 L3 hits B1`).
//!
//! Hits present where a motion starts (the arm already in contact) do not count, so the arm can
//! always be driven out; only new ones do.

use heapless::Vec;

use super::Refusal;
use crate::MAX_JOINTS;
use crate::config::{Envelope, MAX_CAPSULES, Placed, ValidRobot};
use crate::geometry::Capsule;
use crate::kinematics::{Chain, Joints};
use crate::math::Frame;
use armgate_protocol::client::{Hit, PathPoint};

/// The most a capsule may sweep over one piece of a checked joint move (m): the pieces are
/// cut so, up to [`MAX_PATH_SAMPLES`].
pub const SWEEP_STEP: f64 = 0.01;
/// The most pieces of one joint move's check: beyond it the capsules grow by more than half
/// of [`SWEEP_STEP`] (and more pieces are halved).
pub const MAX_PATH_SAMPLES: u16 = 256;
/// How often a piece of a checked joint move may be halved where its grown check hits.
const HALVINGS: u8 = 8;
/// The most checks (a pose and all its pairs) of one joint move: the pieces and their halves.
/// Spent, a piece that would need halving is refused.
pub const MAX_PATH_CHECKS: u16 = 2048;
/// The most hits remembered as already present.
const PRESENT: usize = 8;

/// The body, its checks and the hits already present.
#[derive(Clone, Debug)]
pub struct Body {
    envelope: Envelope,
    /// Per joint: the acceleration a stop brakes with (rad/s² or m/s²).
    a_max: Joints,
    /// Control period (s).
    period: f64,
    /// The hits of the last tick's poses: a stop is for new ones.
    present: Vec<Hit, PRESENT>,
}

impl Body {
    /// The body of a robot.
    pub fn new(config: &ValidRobot) -> Self {
        Self {
            envelope: Envelope::new(config),
            a_max: config.per_joint(|j| j.max_acceleration),
            period: config.control_period,
            present: Vec::new(),
        }
    }

    /// The body model.
    pub fn envelope(&self) -> &Envelope {
        &self.envelope
    }

    /// The capsules at pose `q`, placed by the chain's frames (false if `q` does not fit the
    /// chain).
    pub fn place(&self, chain: &Chain, q: &Joints, out: &mut Placed) -> bool {
        let mut links = [Frame::identity(); MAX_JOINTS];
        let Ok(tool) = chain.link_frames(q, &mut links) else {
            return false;
        };
        let n = chain.dof();
        self.envelope.place_by(
            &|i| match i {
                0 => Some(chain.base()),
                i if i <= n => links.get(i - 1),
                _ => Some(&tool),
            },
            out,
        );
        true
    }

    /// Refuses the joint move from `from` to `to` if a capsule would come within the margin of
    /// a box, the bounds or another capsule on the way, naming the link, the obstacle and
    /// where (percent of the way). Hits present at `from` do not count.
    ///
    /// The way is cut into pieces over which no capsule sweeps more than [`SWEEP_STEP`]; each
    /// piece is checked at its middle with every capsule grown by what it may sweep over half
    /// the piece, which covers the whole piece. A piece whose grown check hits but whose
    /// middle does not is halved and each half checked the same way (down to 1/256 of a
    /// piece; a hit still there refuses), so an arm that starts or passes close to an obstacle
    /// is not refused for the growth alone.
    pub fn check_path(&self, chain: &Chain, from: &Joints, to: &Joints) -> Result<(), Refusal> {
        if self.envelope.is_empty() {
            return Ok(());
        }
        let mut placed = [Capsule::default(); MAX_CAPSULES];
        if !self.place(chain, from, &mut placed) {
            return Ok(());
        }
        let mut start: Vec<Hit, PRESENT> = Vec::new();
        self.envelope
            .hits(&placed, &[0.0; MAX_CAPSULES], &mut |hit, _| {
                start.push(hit).is_ok()
            });
        let mut step = *to;
        for (s, f) in step.iter_mut().zip(from.iter()) {
            *s -= f;
        }
        let mut whole = [0.0; MAX_CAPSULES];
        self.envelope.sweep(&step, &mut whole);
        let longest = whole.iter().fold(0.0f64, |m, s| m.max(*s));
        // Saturating cast: NaN becomes 0, then 1 piece.
        let pieces = ((longest / SWEEP_STEP) as u16).clamp(1, MAX_PATH_SAMPLES);
        let piece = 1.0 / f64::from(pieces);
        let mut budget = MAX_PATH_CHECKS;
        // Pieces still to check, as (start, length) fractions; the nearest first.
        let mut todo: Vec<(f64, f64), { HALVINGS as usize + 2 }> = Vec::new();
        for k in 0..pieces {
            let _ = todo.push((f64::from(k) * piece, piece));
            while let Some((a, length)) = todo.pop() {
                budget = budget.saturating_sub(1);
                let middle = a + 0.5 * length;
                let mut q = *from;
                for (q, s) in q.iter_mut().zip(step.iter()) {
                    *q += middle * s;
                }
                if !self.place(chain, &q, &mut placed) {
                    continue;
                }
                let mut grow = whole;
                for g in &mut grow {
                    *g *= 0.5 * length;
                }
                let new_hit = |grow: &[f64; MAX_CAPSULES]| {
                    let mut found = None;
                    self.envelope.hits(&placed, grow, &mut |hit, _| {
                        if start.contains(&hit) {
                            return true;
                        }
                        found = Some(hit);
                        false
                    });
                    found
                };
                let Some(grown) = new_hit(&grow) else {
                    continue;
                };
                let halves_left = length > piece / f64::from(1u32 << HALVINGS) && budget > 0;
                let refuse = |hit| Err(Refusal::Hits(hit, PathPoint::at(middle)));
                if !halves_left {
                    return refuse(grown);
                }
                if let Some(hit) = new_hit(&[0.0; MAX_CAPSULES]) {
                    return refuse(hit);
                }
                // The far half below the near one: the nearest hit is found first. (The list
                // holds a piece and its halvings by construction; were it full, refuse.)
                let half = 0.5 * length;
                if todo.push((a + half, half)).is_err() || todo.push((a, half)).is_err() {
                    return refuse(grown);
                }
            }
        }
        Ok(())
    }

    /// Checks the tick's command `q` and the pose where a stop from the commanded `velocity`
    /// would end: a hit that was not present at the last check is returned (the caller stops
    /// the motion). Where the stop ends is estimated as the joint-space stop does it: every
    /// joint braking by one fraction, in the time the slowest needs at its acceleration
    /// limit, after the period already commanded: `q + v (T/2 + period)`, `T = max |v|/a`.
    pub fn check_tick(&mut self, chain: &Chain, q: &Joints, velocity: &Joints) -> Option<Hit> {
        if self.envelope.is_empty() {
            return None;
        }
        let brake = velocity
            .iter()
            .zip(self.a_max.iter())
            .fold(0.0f64, |t, (v, a)| t.max(libm::fabs(*v) / a));
        let ahead = 0.5 * brake + self.period;
        let mut rest = *q;
        for (r, v) in rest.iter_mut().zip(velocity.iter()) {
            *r += v * ahead;
        }
        let mut now: Vec<Hit, PRESENT> = Vec::new();
        let mut new = None;
        let mut placed = [Capsule::default(); MAX_CAPSULES];
        // At rest (no velocity) the stop ends where the arm is: one pose to check.
        let poses = if rest == *q { 1 } else { 2 };
        for pose in [q, &rest].into_iter().take(poses) {
            if !self.place(chain, pose, &mut placed) {
                continue;
            }
            let present = &self.present;
            self.envelope
                .hits(&placed, &[0.0; MAX_CAPSULES], &mut |hit, _| {
                    if !present.contains(&hit) && new.is_none() {
                        new = Some(hit);
                    }
                    if !now.contains(&hit) {
                        // Full: the rest are remembered next tick.
                        let _ = now.push(hit);
                    }
                    true
                });
        }
        self.present = now;
        new
    }
}
