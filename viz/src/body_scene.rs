//! The body in a recording: `/body`, the controller's capsules drawn on their link frames
//! with the nearest pair coloured, and `/clearance`, the gaps of every recorded pose.
//!
//! The capsules are frame-locked to the URDF's links (the viewer moves them with `/tf`), so
//! `/body` is written only at the start and when the nearest pair or its colour changes; each
//! message holds the whole body (it deletes all and draws again), so the last one alone shows
//! it, as a live viewer that subscribes late receives it. The gaps are core's own
//! ([`BodyModel::clearance`]).

use armgate_core::config::ValidRobot;
use armgate_core::kinematics::Joints;
use armgate_core::math::Frame;
use armgate_protocol::client::{Hit, Obstacle};
use serde_json::{Value, json};

use crate::body::{BodyModel, Clearance, LinkCapsule, link_capsules};
use crate::foxglove::{self, WORLD};
use crate::urdf;

/// A nearest pair closer than this beyond the margin is drawn amber (m): about what a
/// stop at the arms' teleop speeds travels, where a viewer wants to look.
pub const NEAR: f64 = 0.05;

/// The thinnest a capsule is drawn (radius, m): a capsule of radius 0 (a bare segment, such as
/// ranger-mk1's forearm) would be invisible.
pub const THINNEST: f64 = 0.003;

/// How near the nearest pair is, and its colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Class {
    /// Within the margin (touching when it is 0): red.
    Within,
    /// Within [`NEAR`] beyond the margin: amber.
    Near,
    /// Farther: green.
    Clear,
}

impl Class {
    /// The class of a gap (NaN counts as within).
    pub fn of(gap: f64, margin: f64) -> Self {
        if gap > margin + NEAR {
            Self::Clear
        } else if gap > margin {
            Self::Near
        } else {
            Self::Within
        }
    }

    /// RGBA.
    pub fn color(self) -> [f64; 4] {
        match self {
            Self::Within => [0.9, 0.1, 0.1, 0.8],
            Self::Near => [1.0, 0.65, 0.0, 0.8],
            Self::Clear => [0.2, 0.75, 0.3, 0.6],
        }
    }
}

/// The colour of capsules not in the nearest pair: translucent blue-grey, so the arm's own
/// drawing shows through.
pub const BODY_COLOR: [f64; 4] = [0.35, 0.55, 0.8, 0.35];

/// What `/body` shows now.
type Shown = Option<(Hit, Class)>;

/// The body of one robot, and what its last `/body` message showed.
pub struct BodyView {
    model: BodyModel,
    capsules: Vec<LinkCapsule>,
    boxes: Vec<[f64; 6]>,
    /// None before the first pose.
    shown: Option<Shown>,
}

impl BodyView {
    /// The view of `robot`'s body.
    pub fn new(robot: &ValidRobot) -> Self {
        Self {
            model: BodyModel::new(robot),
            capsules: link_capsules(robot),
            boxes: robot.workspace.boxes.to_vec(),
            shown: None,
        }
    }

    /// The body before any pose (none without a body): for the preamble.
    pub fn preamble(&self, t: f64) -> Option<Value> {
        (!self.model.is_empty()).then(|| self.scene(t, None))
    }

    /// At the measured joints `q`: the `/clearance` message, and a `/body` message if the
    /// nearest pair or its colour changed (none without a body, or if `q` fits no pose).
    pub fn update(&mut self, t: f64, q: &Joints) -> Option<(Value, Option<Value>)> {
        let c = self.model.clearance(q)?;
        let margin = self.model.margin();
        let shown = c.nearest.map(|(gap, hit)| (hit, Class::of(gap, margin)));
        let scene = (self.shown != Some(shown)).then(|| self.scene(t, shown));
        self.shown = Some(shown);
        Some((clearance(t, &c, margin), scene))
    }

    /// The whole body, the pair `shown` coloured.
    fn scene(&self, t: f64, shown: Shown) -> Value {
        let coloured = |link: u8| {
            shown.and_then(|(hit, class)| {
                let pair = hit.link == link || hit.obstacle == Obstacle::Link(link);
                pair.then(|| class.color())
            })
        };
        let mut links: Vec<u8> = self.capsules.iter().map(|c| c.link).collect();
        links.dedup();
        let mut entities: Vec<Value> = links
            .iter()
            .map(|&link| {
                let color = coloured(link).unwrap_or(BODY_COLOR);
                let (mut cylinders, mut spheres, mut numbers) = (vec![], vec![], vec![]);
                for (k, c) in self.capsules.iter().enumerate() {
                    if c.link != link {
                        continue;
                    }
                    numbers.push((k + 1).to_string());
                    let d = 2.0 * c.radius.max(THINNEST);
                    if let Some((frame, length)) = urdf::along(c.a, c.b) {
                        cylinders.push(json!({
                            "pose": foxglove::pose(&frame), "size": xyz([d, d, length]),
                            "bottom_scale": 1.0, "top_scale": 1.0, "color": rgba(color),
                        }));
                    }
                    for p in [c.a, c.b] {
                        spheres.push(json!({
                            "pose": foxglove::pose(&Frame::translation(p.x, p.y, p.z)),
                            "size": xyz([d, d, d]), "color": rgba(color),
                        }));
                    }
                }
                let name = link_frame(link);
                let metadata = [json!({ "key": "capsules", "value": numbers.join(" ") })];
                foxglove::entity(
                    t,
                    &name,
                    &format!("body_{name}"),
                    json!({ "cylinders": cylinders, "spheres": spheres, "metadata": metadata }),
                )
            })
            .collect();
        if let Some((hit, class)) = shown {
            let nearest_box = match hit.obstacle {
                Obstacle::Box(k) => self.boxes.get(usize::from(k).wrapping_sub(1)),
                _ => None,
            };
            if let Some([x0, x1, y0, y1, z0, z1]) = nearest_box {
                // A little larger than the box, so it shows over /workspace's cube.
                let grow = 0.004;
                let centre = Frame::translation(0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.5 * (z0 + z1));
                let size = [x1 - x0 + grow, y1 - y0 + grow, z1 - z0 + grow];
                let cube = json!({ "pose": foxglove::pose(&centre), "size": xyz(size),
                                   "color": rgba(class.color()) });
                entities.push(foxglove::entity(
                    t,
                    WORLD,
                    "nearest_box",
                    json!({ "cubes": [cube] }),
                ));
            }
        }
        json!({
            // Everything drawn before goes: this message is the whole body.
            "deletions": [{ "timestamp": foxglove::time(t), "type": 1, "id": "" }],
            "entities": entities,
        })
    }
}

/// The URDF link carrying core's link `link`.
fn link_frame(link: u8) -> String {
    match usize::from(link) {
        0 => urdf::BASE.to_owned(),
        l => urdf::link_name(l - 1),
    }
}

/// An `armgate.Clearance` (distances in m; null where nothing of the kind is checked).
fn clearance(t: f64, c: &Clearance, margin: f64) -> Value {
    let finite = |v: f64| v.is_finite().then_some(v);
    let (nearest, link, obstacle) = match c.nearest {
        Some((gap, hit)) => (
            finite(gap),
            Some(hit.link),
            Some(match hit.obstacle {
                Obstacle::Box(k) => format!("B{k}"),
                Obstacle::Link(l) => format!("L{l}"),
                Obstacle::Bounds => "bounds".to_owned(),
            }),
        ),
        None => (None, None, None),
    };
    json!({
        "timestamp": foxglove::time(t), "margin": margin, "nearest": nearest,
        "link": link, "obstacle": obstacle, "boxes": finite(c.boxes),
        "bounds": finite(c.bounds), "links": finite(c.links),
    })
}

fn xyz([x, y, z]: [f64; 3]) -> Value {
    json!({ "x": x, "y": y, "z": z })
}

fn rgba([r, g, b, a]: [f64; 4]) -> Value {
    json!({ "r": r, "g": g, "b": b, "a": a })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::indexing_slicing)]
    use super::*;

    fn robot() -> ValidRobot {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../robots/ranger-mk1.toml");
        armgate_core::config::load_file(std::path::Path::new(path)).unwrap()
    }

    #[test]
    fn classes_by_gap() {
        assert_eq!(Class::of(0.0, 0.0), Class::Within);
        assert_eq!(Class::of(-0.1, 0.0), Class::Within);
        assert_eq!(Class::of(0.03, 0.01), Class::Near);
        assert_eq!(Class::of(0.07, 0.01), Class::Clear);
        assert_eq!(Class::of(f64::NAN, 0.0), Class::Within);
    }

    /// The preamble draws every capsule; at home the nearest pair is coloured; the same pose
    /// again writes no scene.
    #[test]
    fn the_scene_changes_with_the_nearest_pair() {
        let robot = robot();
        let mut view = BodyView::new(&robot);
        let preamble = view.preamble(0.0).unwrap();
        let capsules = link_capsules(&robot).len();
        let spheres: usize = preamble["entities"]
            .as_array()
            .unwrap()
            .iter()
            .map(|e| e["spheres"].as_array().unwrap().len())
            .sum();
        assert_eq!(spheres, 2 * capsules);
        let home = robot.home();
        let (clearance, scene) = view.update(0.1, &home).unwrap();
        let scene = scene.unwrap();
        let link = clearance["link"].as_u64().unwrap();
        let coloured: Vec<&Value> = scene["entities"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|e| e["spheres"][0]["color"] != rgba(BODY_COLOR))
            .collect();
        assert!(!coloured.is_empty());
        assert!(
            coloured
                .iter()
                .any(|e| e["frame_id"] == link_frame(link as u8))
        );
        assert!(view.update(0.2, &home).unwrap().1.is_none());
    }

    /// At random poses of every robot with a body: the links of the nearest pair (both, for
    /// two links) carry its class's colour and no other does; a nearest box gets its cube.
    #[test]
    fn exactly_the_nearest_pair_is_coloured() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../robots");
        let mut kinds = std::collections::HashSet::new();
        for entry in std::fs::read_dir(dir).unwrap() {
            let robot = armgate_core::config::load_file(entry.unwrap().path()).unwrap();
            let chain = armgate_core::kinematics::Chain::new(&robot);
            let mut view = BodyView::new(&robot);
            let mut rng = armgate_core::rng::SplitMix64::new(11);
            for k in 0..100 {
                let q = chain.random_joints(&mut rng);
                let (c, scene) = view.update(f64::from(k), &q).unwrap();
                let Some(scene) = scene else { continue };
                let gap = c["nearest"].as_f64().unwrap();
                let colour = rgba(Class::of(gap, c["margin"].as_f64().unwrap()).color());
                let obstacle = c["obstacle"].as_str().unwrap();
                let mut pair = vec![link_frame(c["link"].as_u64().unwrap() as u8)];
                if let Some(l) = obstacle.strip_prefix('L') {
                    pair.push(link_frame(l.parse().unwrap()));
                }
                kinds.insert(obstacle.chars().next().unwrap());
                let entities = scene["entities"].as_array().unwrap();
                for e in entities {
                    let in_pair = e["id"] == "nearest_box"
                        || pair.iter().any(|p| e["frame_id"] == p.as_str());
                    let expected = if in_pair {
                        colour.clone()
                    } else {
                        rgba(BODY_COLOR)
                    };
                    let shapes = ["cubes", "cylinders", "spheres"]
                        .iter()
                        .flat_map(|kind| e[*kind].as_array().unwrap());
                    for shape in shapes {
                        assert_eq!(shape["color"], expected, "{obstacle} {e}");
                    }
                }
                let boxed = entities.iter().any(|e| e["id"] == "nearest_box");
                assert_eq!(boxed, obstacle.starts_with('B'));
                let coloured = entities
                    .iter()
                    .filter(|e| e["id"] != "nearest_box")
                    .filter(|e| e["spheres"][0]["color"] == colour)
                    .count();
                assert_eq!(coloured, pair.len(), "{obstacle}");
            }
        }
        // Random poses of the shipped robots come nearest to boxes, links and the bounds.
        assert_eq!(kinds, ['B', 'L', 'b'].into_iter().collect());
    }
}
