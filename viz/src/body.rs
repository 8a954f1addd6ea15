//! The arm's body as the controller checks it (core's [`Envelope`]): its capsules in their
//! link frames, for the URDF's collision geometry and the recordings' `/body` scene, and the
//! clearances of a pose, measured by core's own [`Envelope::gaps`] (the pairs, boxes and
//! bounds the controller checks, nothing copied).

use armgate_core::config::{Envelope, Frames, MAX_CAPSULES, ValidRobot, frames_at};
use armgate_core::geometry::Capsule;
use armgate_core::kinematics::{Chain, Joints};
use armgate_core::motion::Body;
use armgate_protocol::client::{Hit, Obstacle};
use nalgebra::Vector3;

/// One capsule of the body in the frame of its link.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkCapsule {
    /// The link (0 = base, i = frame {i}; the tool's capsule is on link n).
    pub link: u8,
    /// One end of the axis, in the link's frame (m).
    pub a: Vector3<f64>,
    /// The other end (m).
    pub b: Vector3<f64>,
    /// The radius (m).
    pub radius: f64,
}

/// The body's capsules in core's order, each in its link's frame. Core anchors a capsule's
/// ends in frames of the chain (a DH segment ends at the next joint's origin, the tool's at
/// the tool point); placed by the home pose's frames seen from the capsule's own link, they
/// come out in that link's frame, where they stay in every pose.
pub fn link_capsules(robot: &ValidRobot) -> Vec<LinkCapsule> {
    let envelope = Envelope::new(robot);
    let frames = frames_at(robot, &robot.home());
    (0..envelope.len())
        .filter_map(|i| {
            let link = envelope.link_of(i)?;
            let own = frames.get(usize::from(link))?.inverse();
            let relative: Frames = frames.map(|f| own * f);
            let mut placed = [Capsule::default(); MAX_CAPSULES];
            envelope.place(&relative, &mut placed);
            let c = placed.get(i)?;
            Some(LinkCapsule {
                link,
                a: c.segment.a,
                b: c.segment.b,
                radius: c.radius,
            })
        })
        .collect()
}

/// The gaps of one pose (m; infinite where nothing of the kind is checked).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clearance {
    /// The nearest of all, and between what.
    pub nearest: Option<(f64, Hit)>,
    /// The least gap of a capsule to an exclusion box.
    pub boxes: f64,
    /// The least room of the tool's capsules inside the workspace bounds.
    pub bounds: f64,
    /// The least gap between two capsules checked against each other.
    pub links: f64,
}

/// The body of a robot and the chain that places it, as the control tick has them.
pub struct BodyModel {
    body: Body,
    chain: Chain,
}

impl BodyModel {
    /// The model of `robot`.
    pub fn new(robot: &ValidRobot) -> Self {
        Self {
            body: Body::new(robot),
            chain: Chain::new(robot),
        }
    }

    /// The margin the controller keeps (m).
    pub fn margin(&self) -> f64 {
        self.body.envelope().margin()
    }

    /// True if the body has no capsule (`collision.enabled = false`).
    pub fn is_empty(&self) -> bool {
        self.body.envelope().is_empty()
    }

    /// The capsules placed in the world at pose `q` (core's order); none if `q` does not fit
    /// the chain.
    pub fn placed(&self, q: &Joints) -> Option<Vec<Capsule>> {
        let mut placed = [Capsule::default(); MAX_CAPSULES];
        self.body.place(&self.chain, q, &mut placed).then(|| {
            placed
                .into_iter()
                .take(self.body.envelope().len())
                .collect()
        })
    }

    /// The clearances at pose `q`: every gap the controller checks, by kind, and the nearest.
    pub fn clearance(&self, q: &Joints) -> Option<Clearance> {
        let mut placed = [Capsule::default(); MAX_CAPSULES];
        if self.is_empty() || !self.body.place(&self.chain, q, &mut placed) {
            return None;
        }
        let mut c = Clearance {
            nearest: None,
            boxes: f64::INFINITY,
            bounds: f64::INFINITY,
            links: f64::INFINITY,
        };
        self.body
            .envelope()
            .gaps(&placed, None, f64::INFINITY, &mut |hit, gap, _| {
                let kind = match hit.obstacle {
                    Obstacle::Box(_) => &mut c.boxes,
                    Obstacle::Bounds => &mut c.bounds,
                    Obstacle::Link(_) => &mut c.links,
                };
                *kind = kind.min(gap);
                if c.nearest.is_none_or(|(g, _)| gap < g) {
                    c.nearest = Some((gap, hit));
                }
                true
            });
        Some(c)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::indexing_slicing)]
    use super::*;
    use crate::test_robots::robots;
    use armgate_core::math::Frame;
    use armgate_core::rng::SplitMix64;

    /// The link-frame capsules, carried by the link frames of any pose, are where the tick
    /// places them.
    #[test]
    fn link_capsules_ride_on_their_link_frames() {
        for robot in robots() {
            let capsules = link_capsules(&robot);
            let model = BodyModel::new(&robot);
            assert_eq!(capsules.len(), Envelope::new(&robot).len());
            let mut rng = SplitMix64::new(3);
            for _ in 0..50 {
                let q = model.chain.random_joints(&mut rng);
                let mut links = [Frame::identity(); armgate_core::MAX_JOINTS];
                model.chain.link_frames(&q, &mut links).unwrap();
                let frame = |l: u8| match l {
                    0 => *model.chain.base(),
                    l => links[usize::from(l) - 1],
                };
                let placed = model.placed(&q).unwrap();
                for (c, p) in capsules.iter().zip(&placed) {
                    let f = frame(c.link);
                    let a = f.rotation * c.a + f.translation.vector;
                    let b = f.rotation * c.b + f.translation.vector;
                    let name = robot.name.as_str();
                    assert!((a - p.segment.a).norm() < 1e-12, "{name}");
                    assert!((b - p.segment.b).norm() < 1e-12, "{name}");
                    assert_eq!(c.radius, p.radius);
                }
            }
        }
    }

    /// The nearest gap is core's own `Envelope::nearest`, and the kinds' least gaps hold it.
    #[test]
    fn the_nearest_is_cores_nearest() {
        for robot in robots() {
            let model = BodyModel::new(&robot);
            let envelope = Envelope::new(&robot);
            let mut rng = SplitMix64::new(5);
            for _ in 0..200 {
                let q = model.chain.random_joints(&mut rng);
                let c = model.clearance(&q).unwrap();
                let mut placed = [Capsule::default(); MAX_CAPSULES];
                assert!(model.body.place(&model.chain, &q, &mut placed));
                let (gap, hit) = envelope.nearest(&placed);
                assert_eq!(c.nearest, hit.map(|h| (gap, h)));
                assert_eq!(gap, c.boxes.min(c.bounds).min(c.links));
            }
        }
    }
}
