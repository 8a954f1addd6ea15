//! The whole arm inside the envelope: its body ([`Envelope`], capsules on every link) kept out
//! of the exclusion boxes, inside the bounds and clear of itself (docs/safety.md, "The whole
//! arm inside the envelope").
//!
//! * **Before a joint move starts** ([`Body::check_path`]) its whole straight way in joint
//!   space is checked by conservative advancement: from each checked pose on, the way is
//!   clear as far as the nearest gap can close (a bound from the joint steps and each link's
//!   reach from every axis), so no contact between the checked poses is missed:
//!   `ER25 Cmd jB L3 hits B1 at 40%`.
//! * **Every tick** ([`Body::check_tick`]) the commanded pose and the pose where a stop begun
//!   now would end are checked; a new hit stops the motion (`ER21 L3 hits B1`).
//! * **Streams** look ahead ([`Body::ahead`]) and slow by the nearest gap, the tick's own
//!   check's ([`Body::clearance_at`]); they hold within [`CONTACT`] of the margin
//!   (`WN13 Held: L3 hits B1`). `SQ` 7 reports the nearest gap ([`Body::nearest_at`]).
//!
//! Hits present where a motion starts (the arm already in contact) do not count, so the arm can
//! always be driven out; only new ones do.

use heapless::Vec;

use super::Refusal;
use super::brake::budget;
use crate::MAX_JOINTS;
use crate::config::{Envelope, MAX_CAPSULES, Placed, ValidRobot};
use crate::geometry::Capsule;
use crate::kinematics::{Chain, Joints};
use crate::math::Frame;
use armgate_protocol::client::{Hit, PathPoint};

/// The most poses one joint move's check places, per second of the control period: spent,
/// the move is refused `near edge` at the point reached. One check (a pose, every gap) costs
/// up to about 7,500 Cortex-M7 instructions (ur5, the most pairs; qemu-bench): at 480 MHz
/// this keeps a check within 40 % of the period, the planning request's share of a tick
/// (ur5: 129 checks, ranger-mk1: 497).
pub const CHECKS_PER_SECOND: f64 = 25_600.0;
/// The gap beyond the margin a joint move's check counts as contact (m): advancing towards an
/// obstacle, each step covers a part of the room left, so contact itself is only ever
/// approached; at 1 mm it is called.
pub const CONTACT: f64 = 0.001;
/// The most hits remembered as already present.
pub const PRESENT: usize = 8;

/// The body, its checks and the hits already present.
#[derive(Clone, Debug)]
pub struct Body {
    envelope: Envelope,
    /// Per joint: the acceleration a stop brakes with (rad/s² or m/s²).
    a_max: Joints,
    /// Control period (s).
    period: f64,
    /// The most poses a joint move's check places ([`CHECKS_PER_SECOND`]).
    max_checks: u16,
    /// The hits of the last tick's poses: a stop is for new ones.
    present: Vec<Hit, PRESENT>,
    /// The last tick's command and its nearest gap beyond the margin (m): where a stream's
    /// next tick starts, measured once ([`clearance_at`](Self::clearance_at)).
    clearance: Option<(Joints, f64)>,
}

impl Body {
    /// The body of a robot.
    pub fn new(config: &ValidRobot) -> Self {
        Self {
            envelope: Envelope::new(config),
            a_max: config.per_joint(|j| j.max_acceleration),
            period: config.control_period,
            // Saturating cast: at least one check.
            max_checks: ((config.control_period * CHECKS_PER_SECOND) as u16).max(1),
            present: Vec::new(),
            clearance: None,
        }
    }

    /// The body model.
    pub fn envelope(&self) -> &Envelope {
        &self.envelope
    }

    /// The capsules at pose `q`, placed by the chain's frames (false if `q` does not fit the
    /// chain). Out of line on the microcontroller: one copy of the chain's walk for the
    /// checks' four callers.
    #[cfg_attr(target_os = "none", inline(never))]
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

    /// The most poses a joint move's check places.
    pub fn max_checks(&self) -> u16 {
        self.max_checks
    }

    /// Refuses the joint move from `from` to `to` if a capsule would come within the margin
    /// (and [`CONTACT`]) of a box, the bounds or another capsule on the way, naming the link,
    /// the obstacle and where (percent of the way). What is that near at `from` does not count
    /// if it is a hit there (within the margin); if not, it must not become one.
    ///
    /// Conservative advancement: at each checked pose every gap is measured, and the way is
    /// clear as far as the nearest gap can close at its sweep bound (a joint step Δq moves a
    /// point at most |Δq| times its distance from the joint's axis; a pair counts only the
    /// joints between its links). The next pose is there, so no contact between checked
    /// poses is missed and the steps are long where the arm is far from everything. A way
    /// that needs more than [`max_checks`](Self::max_checks) poses (it grazes something) is
    /// refused `near edge` where the check stopped.
    pub fn check_path(&self, chain: &Chain, from: &Joints, to: &Joints) -> Result<(), Refusal> {
        if self.envelope.is_empty() {
            return Ok(());
        }
        let mut placed = [Capsule::default(); MAX_CAPSULES];
        if !self.place(chain, from, &mut placed) {
            return Ok(());
        }
        // What is within contact at the start: a hit there (within the margin, what the
        // tick's check finds present) does not count, so the arm can be driven out; what is
        // only within `CONTACT` of the margin must not come within the margin (a hit for the
        // tick's check too), else a link 0.9 mm from another was let through it and the tick
        // stopped the move it had accepted (ur5, `L3 hits L0`, issue 35).
        let mut start: Vec<(Hit, bool), PRESENT> = Vec::new();
        let margin = self.envelope.margin();
        self.envelope
            .gaps(&placed, None, CONTACT, &mut |hit, gap, _| {
                start.push((hit, gap <= margin)).is_ok()
            });
        let mut step = *to;
        for (s, f) in step.iter_mut().zip(from.iter()) {
            *s -= f;
        }
        let mut done = 0.0;
        for _ in 0..self.max_checks {
            let mut q = *from;
            for (q, s) in q.iter_mut().zip(step.iter()) {
                *q += done * s;
            }
            if !self.place(chain, &q, &mut placed) {
                return Ok(());
            }
            let (mut advance, mut hit_here) = (f64::INFINITY, None);
            self.envelope.gaps(
                &placed,
                Some(&step),
                f64::INFINITY,
                &mut |hit, gap, rate| {
                    let contact = match start.iter().find(|(h, _)| *h == hit) {
                        Some((_, true)) => return true,
                        Some((_, false)) => 0.0,
                        None => CONTACT,
                    };
                    let room = gap - margin;
                    // Not clear (NaN included): a hit here.
                    if room.is_nan() || room <= contact {
                        hit_here = Some(hit);
                        return false;
                    }
                    advance = advance.min(room / rate);
                    true
                },
            );
            if let Some(hit) = hit_here {
                return Err(Refusal::Hits(hit, PathPoint::at(done)));
            }
            done += advance;
            if done >= 1.0 {
                return Ok(());
            }
        }
        Err(Refusal::NearEdge(PathPoint::at(done)))
    }

    /// The smallest gap at pose `q` (m) and what it is between (`SQ` index 7); none for an
    /// empty body.
    pub fn nearest_at(&self, chain: &Chain, q: &Joints) -> Option<(f64, Hit)> {
        let mut placed = [Capsule::default(); MAX_CAPSULES];
        if !self.place(chain, q, &mut placed) {
            return None;
        }
        let (gap, hit) = self.envelope.nearest(&placed);
        hit.map(|hit| (gap, hit))
    }

    /// The hits at pose `q` (up to [`PRESENT`]): what a motion from there may leave.
    pub fn present_at(&self, chain: &Chain, q: &Joints) -> Vec<Hit, PRESENT> {
        let mut present = Vec::new();
        let mut placed = [Capsule::default(); MAX_CAPSULES];
        if self.place(chain, q, &mut placed) {
            self.envelope
                .hits(&placed, &mut |hit, _| present.push(hit).is_ok());
        }
        present
    }

    /// The first hit at pose `q` that is not in `present`, if any: a point of a Cartesian
    /// line's check.
    pub fn new_hit(&self, chain: &Chain, q: &Joints, present: &[Hit]) -> Option<Hit> {
        let mut placed = [Capsule::default(); MAX_CAPSULES];
        let mut new = None;
        if self.place(chain, q, &mut placed) {
            self.envelope.hits(&placed, &mut |hit, _| {
                if present.contains(&hit) {
                    return true;
                }
                new = Some(hit);
                false
            });
        }
        new
    }

    /// Checks the tick's command `q` and the pose where a stop from the commanded `velocity`
    /// would end: a hit that was not present at the last check is returned (the caller stops
    /// the motion). Where the stop ends is estimated by the supervisor's braking profile: the
    /// speed scale falls by one fraction a tick, as fast as every joint's acceleration limit
    /// and `path_rate` (a Cartesian path's stop also keeps its Cartesian limits: the fall a
    /// tick they allow, [`budget`]; infinite for none) allow, so the stop takes
    /// `T = period / rate` and ends near `q + v (T/2 + period)` (along a path to first order).
    /// `end`: where a motion running along a straight joint line from `q` ends (its goal;
    /// `q` holding). A stop along it brakes on that line and never passes its end, so the
    /// estimate is kept between `q` and `end`, on the way the move's check accepted: unbounded,
    /// it passed the goal by up to `v · period` and more (the estimate overshoots the plan's
    /// own deceleration), off the checked way, and a move the check accepted was stopped
    /// `ER21` near its end (issue 35). Streams and bending ways give none.
    /// With `measure` (a stream runs: it slows by the gap) the command's nearest gap beyond
    /// the margin is kept for [`clearance_at`](Self::clearance_at).
    pub fn check_tick(
        &mut self,
        chain: &Chain,
        q: &Joints,
        (velocity, path_rate): (&Joints, f64),
        end: Option<&Joints>,
        measure: bool,
    ) -> Option<Hit> {
        if self.envelope.is_empty() {
            return None;
        }
        let rate = budget(velocity, &self.a_max, self.period).min(path_rate);
        let ahead = 0.5 * self.period / rate + self.period;
        let mut rest = *q;
        for (r, v) in rest.iter_mut().zip(velocity.iter()) {
            *r += v * ahead;
        }
        if let Some(end) = end {
            for ((r, q), e) in rest.iter_mut().zip(q.iter()).zip(end.iter()) {
                // Not `clamp`: it panics on NaN, and brings float formatting to the board.
                *r = r.max(q.min(*e)).min(q.max(*e));
            }
        }
        let mut now: Vec<Hit, PRESENT> = Vec::new();
        let mut new = None;
        let mut placed = [Capsule::default(); MAX_CAPSULES];
        // At rest (no velocity) the stop ends where the arm is: one pose to check.
        let poses = if rest == *q { 1 } else { 2 };
        self.clearance = None;
        for (k, pose) in [q, &rest].into_iter().take(poses).enumerate() {
            if !self.place(chain, pose, &mut placed) {
                continue;
            }
            let present = &self.present;
            // Every hit is visited, so what is not is beyond the margin: its nearest is the
            // command's gap, measured by the check anyway.
            let beyond = self.envelope.gaps(&placed, None, 0.0, &mut |hit, _, _| {
                if !present.contains(&hit) && new.is_none() {
                    new = Some(hit);
                }
                if !now.contains(&hit) {
                    // Full: the rest are remembered next tick.
                    let _ = now.push(hit);
                }
                true
            });
            if k == 0 && measure {
                self.clearance = Some((*q, beyond));
            }
        }
        self.present = now;
        new
    }

    /// The nearest gap beyond the margin (m, infinite for none) at `q`, if `q` is the command
    /// the last tick checked: a stream's tick starts from there.
    pub fn clearance_at(&self, q: &Joints) -> Option<f64> {
        self.clearance
            .filter(|(checked, _)| checked == q)
            .map(|(_, gap)| gap)
    }

    /// A stream's look ahead: at `rest` (where a stop begun after its tick would end), the
    /// first thing a link would come within [`CONTACT`] of the margin of that it is not that
    /// near at `q` (the stream holds before it), and the nearest gap beyond the margin (m,
    /// infinite for none; the stream slows by it). One placement of `rest`; `q` is placed
    /// only if `rest` has anything that near.
    pub fn ahead(&self, chain: &Chain, q: &Joints, rest: &Joints) -> (Option<Hit>, f64) {
        let mut placed = [Capsule::default(); MAX_CAPSULES];
        if self.envelope.is_empty() || !self.place(chain, rest, &mut placed) {
            return (None, f64::INFINITY);
        }
        let margin = self.envelope.margin();
        let (mut near, mut nearest): (Vec<Hit, PRESENT>, _) = (Vec::new(), f64::INFINITY);
        // Those within contact are visited; the rest's nearest comes back.
        let beyond = self
            .envelope
            .gaps(&placed, None, CONTACT, &mut |hit, gap, _| {
                if gap > margin {
                    nearest = nearest.min(gap);
                }
                // Full: the first ones are named.
                let _ = near.push(hit);
                true
            });
        let nearest = nearest.min(beyond);
        if near.is_empty() || !self.place(chain, q, &mut placed) {
            return (near.first().copied(), nearest);
        }
        let mut now: Vec<Hit, PRESENT> = Vec::new();
        self.envelope
            .gaps(&placed, None, CONTACT, &mut |hit, _, _| {
                now.push(hit).is_ok()
            });
        // By reference: heapless's `IntoIter` drops what it did not yield through a slice
        // index, a panic path panic-check found.
        (near.iter().find(|h| !now.contains(h)).copied(), nearest)
    }
}
