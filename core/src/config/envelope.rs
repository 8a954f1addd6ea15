//! The arm's body: capsules fixed to its links, and what each is checked against.
//!
//! Built once from the robot file ([`Envelope::new`]); each check takes the link frames of a
//! pose (from the chain every tick, from [`frames_at`] when the file is validated) and places
//! the capsules in the world. Links are numbered from 0 (the base, frame {0}) to n (frame {n},
//! which also carries the tool).
//!
//! * **Default geometry**: joint i's DH row joins frame {i−1}'s origin to {i}'s by two
//!   segments, `a` along {i−1}'s x axis and `d` along {i}'s z axis; both belong to link i−1.
//!   Segments shorter than 5 mm are left out (a calibration's offsets), and so is a prismatic joint's travel (its `d`), which
//!   no fixed segment describes: give its rail by hand. The tool is one capsule from {n}'s origin to the
//!   tool point. Radii: `[[joints]] link_radius` (link i), `collision.base_radius` (link 0),
//!   `collision.tool_radius`.
//! * **Pairs** of capsules are checked unless they belong to the same link, to adjacent links
//!   (also across links without any capsule: a wrist's centre), to a listed pair, or both never
//!   move.
//! * **Boxes** are checked against every capsule except where a capsule has an end fixed in
//!   the world (within about 1 cm of every joint axis before it) within the box: the links the box's column
//!   carries (the base, a shoulder), which no pose can take out of it.
//! * **Bounds** hold the tool: its capsules (link n's) must stay inside. Bounds are drawn
//!   around the tool's reach (ur5's calibration poses put the wrist's capsules past them while
//!   the tool point is inside); a floor or wall the whole arm must clear is a box.

use heapless::Vec;

use super::collision::{DEFAULT_LINK_RADIUS, MAX_CUSTOM_CAPSULES};
use super::{JointType, RobotConfig};
use crate::MAX_JOINTS;
use crate::geometry::{Capsule, Segment, point_box};
use crate::math::{Frame, Rotation3, Vector3};
use armgate_protocol::client::{Hit, Obstacle};

/// Most capsules of one body: two segments a joint, the tool, and those given by hand.
pub const MAX_CAPSULES: usize = 2 * MAX_JOINTS + 1 + MAX_CUSTOM_CAPSULES;
/// Most pairs of capsules checked against each other.
const MAX_PAIRS: usize = MAX_CAPSULES * (MAX_CAPSULES - 1) / 2;
/// The frames of a pose: {0} (the base in the world), {1}..{n}, then the tool's at index
/// n + 1 (entries past it unused).
pub type Frames = [Frame; MAX_JOINTS + 2];
/// Capsules placed in the world, one per [`Envelope`] capsule, in its order.
pub type Placed = [Capsule; MAX_CAPSULES];
/// DH segments shorter than this are left out of the default body (m): a calibrated file's
/// sub-millimetre offsets would otherwise put a capsule of a link's whole radius where the
/// arm has no link of its own (ranger-mk1's wrist centre, 2 mm above its column at home).
const SHORTEST_SEGMENT: f64 = 0.005;
/// How far a joint is moved to find the points it moves (rad or m).
const PROBE: f64 = 0.5;
/// A point moved by less than this under every probe counts as fixed (m): it lies within
/// about 1 cm of every joint axis before it, so a calibrated file's sub-millimetre offsets
/// (`armgate calibrate`) do not take the shoulder out of the column that carries it.
const FIXED: f64 = 0.005;

/// A point fixed in one of the frames.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Anchor {
    frame: u8,
    point: Vector3<f64>,
}

/// One capsule of the body.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct BodyCapsule {
    link: u8,
    a: Anchor,
    b: Anchor,
    radius: f64,
    /// Per joint: how far from that joint's axis any point of the capsule can be, in every
    /// pose (m; 1 for a prismatic joint that moves it, 0 for a joint that does not): a joint
    /// step of Δq moves no point of the capsule further than `reach × |Δq|`.
    reach: [f64; MAX_JOINTS],
    /// Boxes (bit k: box k) the capsule is not checked against: it has an end fixed in the
    /// world within the box.
    mounted: u16,
    /// Both ends fixed in the world: it never moves.
    fixed: bool,
}

/// The body model of one arm: its capsules, the pairs and boxes they are checked against, the
/// bounds and the margin.
#[derive(Clone, Debug, PartialEq)]
pub struct Envelope {
    capsules: Vec<BodyCapsule, MAX_CAPSULES>,
    pairs: Vec<[u8; 2], MAX_PAIRS>,
    bounds: [f64; 6],
    boxes: Vec<[f64; 6], { super::MAX_BOXES }>,
    margin: f64,
    /// The tool's link (n): only its capsules are held to the bounds.
    tool: u8,
}

impl Envelope {
    /// The body of a robot description (its values checked for finiteness beforehand); empty
    /// when `collision.enabled` is false.
    pub fn new(config: &RobotConfig) -> Self {
        let mut envelope = Self {
            capsules: Vec::new(),
            pairs: Vec::new(),
            bounds: config.workspace.bounds,
            boxes: config.workspace.boxes.clone(),
            margin: config.collision.margin,
            tool: config.joints.len().min(MAX_JOINTS) as u8,
        };
        if !config.collision.enabled {
            return envelope;
        }
        envelope.add_capsules(config);
        envelope.find_fixed(config);
        envelope.add_pairs(config);
        envelope
    }

    /// The number of capsules.
    pub fn len(&self) -> usize {
        self.capsules.len()
    }

    /// True if the body has no capsule (`collision.enabled = false`).
    pub fn is_empty(&self) -> bool {
        self.capsules.is_empty()
    }

    /// The number of capsule pairs checked against each other.
    pub fn pair_count(&self) -> usize {
        self.pairs.len()
    }

    /// The margin kept (m).
    pub fn margin(&self) -> f64 {
        self.margin
    }

    /// The link capsule `index` belongs to.
    pub fn link_of(&self, index: usize) -> Option<u8> {
        self.capsules.get(index).map(|c| c.link)
    }

    fn add_capsules(&mut self, config: &RobotConfig) {
        let n = config.joints.len().min(MAX_JOINTS);
        let collision = &config.collision;
        let custom = |link: usize| {
            collision
                .capsules
                .iter()
                .any(|c| usize::from(c.link) == link)
        };
        let radius = |link: usize| match link.checked_sub(1) {
            None => collision.base_radius,
            Some(j) => config
                .joints
                .get(j)
                .and_then(|j| j.link_radius)
                .unwrap_or(DEFAULT_LINK_RADIUS),
        };
        let at = |frame: usize, x: f64| Anchor {
            frame: frame as u8,
            point: Vector3::new(x, 0.0, 0.0),
        };
        for (i, joint) in config.joints.iter().enumerate().take(n) {
            if custom(i) {
                continue;
            }
            let corner = at(i, joint.a);
            if libm::fabs(joint.a) >= SHORTEST_SEGMENT {
                self.push(i, at(i, 0.0), corner, radius(i));
            }
            if libm::fabs(joint.d) >= SHORTEST_SEGMENT && joint.kind == JointType::Revolute {
                self.push(i, corner, at(i + 1, 0.0), radius(i));
            }
        }
        if !custom(n) {
            self.push(n, at(n, 0.0), at(n + 1, 0.0), collision.tool_radius);
        }
        for c in &collision.capsules {
            let frame = usize::from(c.link);
            let end = |p: [f64; 3]| Anchor {
                frame: c.link,
                point: Vector3::from(p),
            };
            self.push(frame, end(c.from), end(c.to), c.radius);
        }
    }

    fn push(&mut self, link: usize, a: Anchor, b: Anchor, radius: f64) {
        let capsule = BodyCapsule {
            link: link as u8,
            a,
            b,
            radius,
            ..BodyCapsule::default()
        };
        // Capacity: two a joint, the tool and the hand-given ones, by construction.
        let _ = self.capsules.push(capsule);
    }

    /// Which ends are fixed in the world, the boxes they mount capsules in, and each
    /// capsule's reach from every joint's axis.
    fn find_fixed(&mut self, config: &RobotConfig) {
        let home = config.home();
        let frames = frames_at(config, &home);
        let mut moved = [[false; 2]; MAX_CAPSULES];
        for j in 0..config.joints.len().min(MAX_JOINTS) {
            let mut q = home;
            if let Some(v) = q.get_mut(j) {
                *v += PROBE;
            }
            let probed = frames_at(config, &q);
            for (c, moved) in self.capsules.iter().zip(moved.iter_mut()) {
                for (end, m) in [c.a, c.b].iter().zip(moved.iter_mut()) {
                    *m |= (place(&probed, end) - place(&frames, end)).norm() > FIXED;
                }
            }
        }
        let lengths = link_lengths(config);
        let (boxes, margin) = (&self.boxes, self.margin);
        for (c, moved) in self.capsules.iter_mut().zip(moved) {
            c.fixed = !moved[0] && !moved[1];
            for (end, moved) in [c.a, c.b].iter().zip(moved) {
                if moved {
                    continue;
                }
                let p = place(&frames, end);
                for (k, bx) in boxes.iter().enumerate() {
                    if point_box(&p, bx) <= c.radius + margin {
                        c.mounted |= box_bit(k);
                    }
                }
            }
            c.reach = reach(config, &lengths, c);
        }
    }

    fn add_pairs(&mut self, config: &RobotConfig) {
        let mut has_capsule = [false; MAX_JOINTS + 1];
        for c in &self.capsules {
            if let Some(h) = has_capsule.get_mut(usize::from(c.link)) {
                *h = true;
            }
        }
        let adjacent = |a: u8, b: u8| {
            let (lo, hi) = (usize::from(a.min(b)), usize::from(a.max(b)));
            has_capsule
                .get(lo + 1..hi)
                .is_none_or(|between| !between.iter().any(|h| *h))
        };
        let excluded = |a: u8, b: u8| {
            config
                .collision
                .exclude
                .iter()
                .any(|&[x, y]| (x, y) == (a, b) || (y, x) == (a, b))
        };
        for (i, ci) in self.capsules.iter().enumerate() {
            for (j, cj) in self.capsules.iter().enumerate().skip(i + 1) {
                let skip = ci.link == cj.link
                    || adjacent(ci.link, cj.link)
                    || excluded(ci.link, cj.link)
                    || (ci.fixed && cj.fixed);
                if !skip {
                    let _ = self.pairs.push([i as u8, j as u8]);
                }
            }
        }
    }

    /// The capsules placed by the frames of a pose (`out[..len()]`).
    pub fn place(&self, frames: &Frames, out: &mut Placed) {
        self.place_by(&|i| frames.get(i), out);
    }

    /// [`place`](Self::place) with frame `i` (as in [`Frames`]) from `frame(i)`: the tick's
    /// chain hands its link frames over where they are, without gathering them first.
    pub fn place_by<'a>(&self, frame: &dyn Fn(usize) -> Option<&'a Frame>, out: &mut Placed) {
        let at = |anchor: &Anchor| point_in(frame(usize::from(anchor.frame)), anchor);
        for (c, o) in self.capsules.iter().zip(out.iter_mut()) {
            *o = Capsule {
                segment: Segment::new(at(&c.a), at(&c.b)),
                radius: c.radius,
            };
        }
    }

    /// How far capsule `index` can sweep when the joints step by `step` (m), relative to link
    /// `inner`'s frame (0: the world): no point of it moves further over the step, whatever
    /// the pose. Joint k moves links k+1 onwards, so against a capsule on link `inner` only
    /// the joints from `inner`'s on count: under the others both move as one and their gap
    /// stays as it is (ur5's wrist capsules, 1.2 cm apart whatever joint 5 does, were grown by
    /// the whole arm's sweep and refused `L6 hits L4`).
    pub fn sweep(&self, index: usize, step: &[f64], inner: u8) -> f64 {
        self.capsules.get(index).map_or(0.0, |c| {
            let moving = c.reach.iter().zip(step).skip(usize::from(inner));
            moving.map(|(r, dq)| r * libm::fabs(*dq)).sum()
        })
    }

    /// Calls `visit(hit, gap, rate)` for everything the placed capsules are checked against
    /// whose gap (m) is within `within` of the margin, until `visit` returns false: each
    /// capsule against the boxes (and the tool's against the bounds' faces), and each pair.
    /// `rate`: how far the gap can close when the joints step by `step` (0 without one).
    /// Returns the smallest gap of those not visited (infinite for none), up to where `visit`
    /// stopped: a stream's nearest gap beyond the margin, without a call for every gap. Out
    /// of line on the microcontroller: one copy for its callers.
    #[cfg_attr(target_os = "none", inline(never))]
    pub fn gaps(
        &self,
        placed: &Placed,
        step: Option<&[f64]>,
        within: f64,
        visit: &mut dyn FnMut(Hit, f64, f64) -> bool,
    ) -> f64 {
        let near = self.margin + within;
        let mut beyond = f64::INFINITY;
        let rate = |i: usize, inner: u8| step.map_or(0.0, |s| self.sweep(i, s, inner));
        for (i, (c, p)) in self.capsules.iter().zip(placed).enumerate() {
            if c.link == self.tool {
                let gap = p.clearance_in(&self.bounds);
                if gap <= near {
                    if !visit(hit(c.link, Obstacle::Bounds), gap, rate(i, 0)) {
                        return beyond;
                    }
                } else {
                    beyond = beyond.min(gap);
                }
            }
            for (k, bx) in self.boxes.iter().enumerate() {
                if c.mounted & box_bit(k) != 0 {
                    continue;
                }
                let gap = p.gap_to_box(bx);
                let obstacle = Obstacle::Box((k as u8).saturating_add(1));
                if gap <= near {
                    if !visit(hit(c.link, obstacle), gap, rate(i, 0)) {
                        return beyond;
                    }
                } else {
                    beyond = beyond.min(gap);
                }
            }
        }
        for &[i, j] in &self.pairs {
            let (i, j) = (usize::from(i), usize::from(j));
            let (Some(a), Some(b)) = (self.capsules.get(i), self.capsules.get(j)) else {
                continue;
            };
            let (Some(pa), Some(pb)) = (placed.get(i), placed.get(j)) else {
                continue;
            };
            let gap = pa.gap_to_capsule(pb);
            // Named from the outer link, against the inner one: `L5 hits L2`; the outer one
            // moves against the inner one's frame.
            let (outer, inner) = if a.link > b.link { (i, b) } else { (j, a) };
            let name = hit(a.link.max(b.link), Obstacle::Link(inner.link));
            if gap <= near {
                if !visit(name, gap, rate(outer, inner.link)) {
                    return beyond;
                }
            } else {
                beyond = beyond.min(gap);
            }
        }
        beyond
    }

    /// Calls `visit` with every hit of the placed capsules and the gap it was found at, until
    /// `visit` returns false: a capsule within the margin of a box (the tool's: of the bounds'
    /// faces), or of another capsule it is checked against (touching included: with the
    /// margin 0, a gap of 0 is a hit).
    pub fn hits(&self, placed: &Placed, visit: &mut dyn FnMut(Hit, f64) -> bool) {
        self.gaps(placed, None, 0.0, &mut |hit, gap, _| visit(hit, gap));
    }

    /// The first hit of the placed capsules, if any: the check of a pose at rest (a robot
    /// file's home, a calibration plan's poses).
    pub fn first_hit(&self, placed: &Placed) -> Option<Hit> {
        let mut first = None;
        self.hits(placed, &mut |hit, _| {
            first = Some(hit);
            false
        });
        first
    }

    /// The smallest gap of the placed capsules to anything they are checked against (m;
    /// infinite for an empty body), and to what.
    pub fn nearest(&self, placed: &Placed) -> (f64, Option<Hit>) {
        let mut nearest = (f64::INFINITY, None);
        self.gaps(placed, None, f64::INFINITY, &mut |hit, gap, _| {
            if gap < nearest.0 {
                nearest = (gap, Some(hit));
            }
            true
        });
        nearest
    }
}

/// Box `k`'s bit in [`BodyCapsule::mounted`] (none past the 16 a file may hold).
fn box_bit(k: usize) -> u16 {
    u32::try_from(k)
        .ok()
        .and_then(|k| 1u16.checked_shl(k))
        .unwrap_or(0)
}

fn hit(link: u8, obstacle: Obstacle) -> Hit {
    Hit { link, obstacle }
}

/// An anchor's point in the world.
fn place(frames: &Frames, anchor: &Anchor) -> Vector3<f64> {
    point_in(frames.get(usize::from(anchor.frame)), anchor)
}

/// An anchor's point, its frame given.
fn point_in(frame: Option<&Frame>, anchor: &Anchor) -> Vector3<f64> {
    frame.map_or(anchor.point, |f| {
        f.rotation * anchor.point + f.translation.vector
    })
}

/// The longest the way from frame {i}'s origin to {i+1}'s can be, for i = 0..n (the last:
/// to the tool point), whatever the pose.
fn link_lengths(config: &RobotConfig) -> [f64; MAX_JOINTS + 1] {
    let mut lengths = [0.0; MAX_JOINTS + 1];
    for (l, joint) in lengths.iter_mut().zip(&config.joints) {
        let d = match joint.kind {
            JointType::Revolute => libm::fabs(joint.d),
            JointType::Prismatic => {
                libm::fabs(joint.d + joint.min).max(libm::fabs(joint.d + joint.max))
            }
        };
        *l = libm::fabs(joint.a) + d;
    }
    let tool = &config.tool;
    let xyz = Vector3::from(tool.xyz).norm();
    if let Some(l) = lengths.get_mut(config.joints.len()) {
        *l = libm::fabs(tool.a) + libm::fabs(tool.d) + xyz;
    }
    lengths
}

/// A capsule's reach from every joint's axis (see [`BodyCapsule::reach`]): joint j turns
/// frames {j+1} onwards about an axis through {j+1}'s origin, and a point fixed in {f} lies at
/// most the lengths of the links between, plus its own offset, from that origin.
fn reach(
    config: &RobotConfig,
    lengths: &[f64; MAX_JOINTS + 1],
    c: &BodyCapsule,
) -> [f64; MAX_JOINTS] {
    let mut reach = [0.0; MAX_JOINTS];
    for (j, (r, joint)) in reach.iter_mut().zip(&config.joints).enumerate() {
        for end in [c.a, c.b] {
            let frame = usize::from(end.frame);
            if frame <= j {
                continue;
            }
            let far = match joint.kind {
                JointType::Prismatic => 1.0,
                JointType::Revolute => {
                    let between: f64 = lengths.get(j + 1..frame).map_or(0.0, |l| l.iter().sum());
                    between + end.point.norm()
                }
            };
            *r = f64::max(*r, far);
        }
    }
    reach
}

/// The frames of the pose `q` (one value per joint; missing ones count as 0): the robot
/// file's DH product, for checks before a [`Chain`](crate::kinematics::Chain) can exist
/// (validation) and for tests. The tick takes its frames from the chain's faster walk; the
/// kinematics tests check both agree.
pub fn frames_at(config: &RobotConfig, q: &[f64]) -> Frames {
    let mut frames = [Frame::identity(); MAX_JOINTS + 2];
    let mut frame = config.base_frame();
    if let Some(f) = frames.first_mut() {
        *f = frame;
    }
    let n = config.joints.len().min(MAX_JOINTS);
    for (i, joint) in config.joints.iter().enumerate().take(n) {
        let v = q.get(i).copied().unwrap_or(0.0);
        frame *= joint.frame(v);
        if let Some(f) = frames.get_mut(i + 1) {
            *f = frame;
        }
    }
    if let Some(f) = frames.get_mut(n + 1) {
        *f = frame * config.tool.frame();
    }
    frames
}

/// `RotY(beta)`, Hayati's calibration angle.
pub(super) fn tilt(beta: f64) -> Frame {
    Frame::from_parts(
        Vector3::zeros().into(),
        Rotation3::from_axis_angle(&Vector3::y_axis(), beta),
    )
}
