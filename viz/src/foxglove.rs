//! The channels of a recording or live view, and their messages in Foxglove's JSON encoding.
//!
//! Foxglove recognises a schema by its name (`foxglove.JointStates`, `foxglove.FrameTransforms`,
//! …) and draws it without configuration; the JSON Schemas here list the fields armgate
//! writes. The raw datagrams and CAN frames have schemas of their own (`armgate.…`).

use armgate_core::math::Frame;
use base64::Engine as _;
use nalgebra::UnitQuaternion;
use serde_json::{Value, json};

/// The frame everything is expressed in: the robot file's world (the base frame without
/// `[base]`), the URDF's root link.
pub const WORLD: &str = crate::urdf::WORLD;

/// One channel of a recording.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Topic {
    /// The URDF (`foxglove.RobotDescription`), once at the start.
    RobotDescription,
    /// The measured joints, every tick.
    JointStates,
    /// The joint command sent to the drives, every tick that has one (none while off).
    JointCommand,
    /// World → base → every link → tool at the measured joints, every tick.
    Transforms,
    /// The measured tool pose as the controller computes it (what `PS` answers).
    ToolPose,
    /// The Cartesian set-point given to the IK (Cartesian mode).
    Setpoint,
    /// The goal of a move when it begins.
    Goal,
    /// The tool path planned to that goal (a straight line for Cartesian moves, the FK of the
    /// straight joint-space line for joint moves).
    PlannedPath,
    /// The workspace bounds and exclusion boxes, once at the start.
    Workspace,
    /// The arm's body (core's capsules, fixed to the link frames) with the nearest pair
    /// coloured: at the start and whenever the nearest pair or its colour changes.
    Body,
    /// The gaps the controller checks at the measured joints: the nearest and between what,
    /// and the least to the boxes, the bounds and between links, with the margin.
    Clearance,
    /// Every request, reply and notice, decoded.
    Log,
    /// Every client datagram, raw.
    Udp,
    /// Every CAN frame, raw.
    Can,
}

impl Topic {
    /// Every channel, in the order they are registered.
    pub const ALL: [Self; 14] = [
        Self::RobotDescription,
        Self::JointStates,
        Self::JointCommand,
        Self::Transforms,
        Self::ToolPose,
        Self::Setpoint,
        Self::Goal,
        Self::PlannedPath,
        Self::Workspace,
        Self::Body,
        Self::Clearance,
        Self::Log,
        Self::Udp,
        Self::Can,
    ];

    /// The topic name.
    pub const fn name(self) -> &'static str {
        match self {
            Self::RobotDescription => "/robot_description",
            Self::JointStates => "/joint_states",
            Self::JointCommand => "/joint_command",
            Self::Transforms => "/tf",
            Self::ToolPose => "/tool_pose",
            Self::Setpoint => "/setpoint",
            Self::Goal => "/goal",
            Self::PlannedPath => "/planned_path",
            Self::Workspace => "/workspace",
            Self::Body => "/body",
            Self::Clearance => "/clearance",
            Self::Log => "/log",
            Self::Udp => "/udp",
            Self::Can => "/can",
        }
    }

    /// The schema name (Foxglove's own where one fits).
    pub const fn schema_name(self) -> &'static str {
        match self {
            Self::RobotDescription => "foxglove.RobotDescription",
            Self::JointStates | Self::JointCommand => "foxglove.JointStates",
            Self::Transforms => "foxglove.FrameTransforms",
            Self::ToolPose | Self::Setpoint | Self::Goal => "foxglove.PoseInFrame",
            Self::PlannedPath => "foxglove.PosesInFrame",
            Self::Workspace | Self::Body => "foxglove.SceneUpdate",
            Self::Clearance => "armgate.Clearance",
            Self::Log => "foxglove.Log",
            Self::Udp => "armgate.Datagram",
            Self::Can => "armgate.CanFrame",
        }
    }

    /// The JSON Schema of the messages.
    pub fn schema(self) -> String {
        let body = match self {
            Self::RobotDescription => object(&[
                ("url", r#"{"type":"string"}"#),
                ("format", r#"{"type":"string"}"#),
                ("data", r#"{"type":"string","contentEncoding":"base64"}"#),
            ]),
            Self::JointStates | Self::JointCommand => object(&[
                ("timestamp", TIME),
                (
                    "joints",
                    r#"{"type":"array","items":{"type":"object","properties":{"name":{"type":"string"},"position":{"type":"number"}}}}"#,
                ),
            ]),
            Self::Transforms => format!(
                r#"{{"type":"object","properties":{{"transforms":{{"type":"array","items":{}}}}}}}"#,
                object(&[
                    ("timestamp", TIME),
                    ("parent_frame_id", r#"{"type":"string"}"#),
                    ("child_frame_id", r#"{"type":"string"}"#),
                    ("translation", VECTOR3),
                    ("rotation", QUATERNION),
                ])
            ),
            Self::ToolPose | Self::Setpoint | Self::Goal => object(&[
                ("timestamp", TIME),
                ("frame_id", r#"{"type":"string"}"#),
                ("pose", &pose_schema()),
            ]),
            Self::PlannedPath => object(&[
                ("timestamp", TIME),
                ("frame_id", r#"{"type":"string"}"#),
                (
                    "poses",
                    &format!(r#"{{"type":"array","items":{}}}"#, pose_schema()),
                ),
            ]),
            Self::Workspace | Self::Body => SCENE_UPDATE.to_owned(),
            Self::Clearance => object(&[
                ("timestamp", TIME),
                ("margin", NUMBER),
                ("nearest", NUMBER),
                ("link", r#"{"type":["integer","null"]}"#),
                ("obstacle", r#"{"type":["string","null"]}"#),
                ("boxes", NUMBER),
                ("bounds", NUMBER),
                ("links", NUMBER),
            ]),
            Self::Log => object(&[
                ("timestamp", TIME),
                ("level", r#"{"type":"integer"}"#),
                ("message", r#"{"type":"string"}"#),
                ("name", r#"{"type":"string"}"#),
                ("file", r#"{"type":"string"}"#),
                ("line", r#"{"type":"integer"}"#),
            ]),
            Self::Udp => object(&[
                ("timestamp", TIME),
                ("from", r#"{"type":"string"}"#),
                ("to", r#"{"type":"string"}"#),
                ("hex", r#"{"type":"string"}"#),
            ]),
            Self::Can => object(&[
                ("timestamp", TIME),
                ("id", r#"{"type":"integer"}"#),
                ("hex", r#"{"type":"string"}"#),
            ]),
        };
        // The title is the schema's name, as Foxglove's own JSON Schemas have it.
        format!(
            r#"{{"title":"{}",{}"#,
            self.schema_name(),
            body.strip_prefix('{').unwrap_or(&body)
        )
    }
}

const TIME: &str =
    r#"{"type":"object","properties":{"sec":{"type":"integer"},"nsec":{"type":"integer"}}}"#;
/// A distance (m); null where nothing of the kind is checked.
const NUMBER: &str = r#"{"type":["number","null"]}"#;
const VECTOR3: &str = r#"{"type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},"z":{"type":"number"}}}"#;
const QUATERNION: &str = r#"{"type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},"z":{"type":"number"},"w":{"type":"number"}}}"#;
/// The parts of `foxglove.SceneUpdate` used: entities of cubes (the exclusion boxes), lines
/// (the workspace's edges), cylinders and spheres (the body's capsules).
const SCENE_UPDATE: &str = r#"{"type":"object","properties":{"deletions":{"type":"array"},"entities":{"type":"array","items":{"type":"object","properties":{"timestamp":{"type":"object"},"frame_id":{"type":"string"},"id":{"type":"string"},"lifetime":{"type":"object"},"frame_locked":{"type":"boolean"},"metadata":{"type":"array"},"arrows":{"type":"array"},"cubes":{"type":"array"},"spheres":{"type":"array"},"cylinders":{"type":"array"},"lines":{"type":"array"},"triangles":{"type":"array"},"texts":{"type":"array"},"models":{"type":"array"}}}}}}"#;

fn pose_schema() -> String {
    object(&[("position", VECTOR3), ("orientation", QUATERNION)])
}

/// `{"type":"object","properties":{…}}` of these fields.
fn object(fields: &[(&str, &str)]) -> String {
    let fields: Vec<String> = fields
        .iter()
        .map(|(name, schema)| format!(r#""{name}":{schema}"#))
        .collect();
    format!(
        r#"{{"type":"object","properties":{{{}}}}}"#,
        fields.join(",")
    )
}

/// Seconds as Foxglove's `{sec, nsec}` (times before 0 are 0).
pub fn time(t: f64) -> Value {
    let ns = nanos(t);
    json!({ "sec": ns / 1_000_000_000, "nsec": ns % 1_000_000_000 })
}

/// Seconds as whole nanoseconds (the MCAP log time), saturating; negative and NaN are 0.
pub fn nanos(t: f64) -> u64 {
    // `as` saturates and maps NaN to 0.
    (t * 1e9).round() as u64
}

/// A `foxglove.JointStates` of `names` at `positions`.
pub fn joint_states(t: f64, names: &[String], positions: &[f64]) -> Value {
    let joints: Vec<Value> = names
        .iter()
        .zip(positions)
        .map(|(name, q)| json!({ "name": name, "position": q }))
        .collect();
    json!({ "timestamp": time(t), "joints": joints })
}

/// Position and orientation (`Vector3`, `Quaternion`) of a frame.
fn parts(frame: &Frame) -> (Value, Value) {
    let p = frame.translation.vector;
    let q = UnitQuaternion::from_rotation_matrix(&frame.rotation);
    (
        json!({ "x": p.x, "y": p.y, "z": p.z }),
        json!({ "x": q.i, "y": q.j, "z": q.k, "w": q.w }),
    )
}

/// A `foxglove.Pose` of a frame.
pub fn pose(frame: &Frame) -> Value {
    let (position, orientation) = parts(frame);
    json!({ "position": position, "orientation": orientation })
}

/// A `foxglove.FrameTransforms`: each `(parent, child, child in parent)`.
pub fn frame_transforms(t: f64, transforms: &[(&str, &str, Frame)]) -> Value {
    let list: Vec<Value> = transforms
        .iter()
        .map(|(parent, child, frame)| {
            let (translation, rotation) = parts(frame);
            json!({
                "timestamp": time(t),
                "parent_frame_id": parent,
                "child_frame_id": child,
                "translation": translation,
                "rotation": rotation,
            })
        })
        .collect();
    json!({ "transforms": list })
}

/// A `foxglove.PoseInFrame` in the world frame.
pub fn pose_in_frame(t: f64, frame: &Frame) -> Value {
    json!({ "timestamp": time(t), "frame_id": WORLD, "pose": pose(frame) })
}

/// A `foxglove.PosesInFrame` in the world frame.
pub fn poses_in_frame(t: f64, frames: &[Frame]) -> Value {
    let poses: Vec<Value> = frames.iter().map(pose).collect();
    json!({ "timestamp": time(t), "frame_id": WORLD, "poses": poses })
}

/// `foxglove.Log` levels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Level {
    /// Requests and replies.
    Info = 2,
    /// `WN` notices.
    Warning = 3,
    /// `ER` texts.
    Error = 4,
}

/// A `foxglove.Log` line from `name` (who sent it).
pub fn log(t: f64, level: Level, name: &str, message: &str) -> Value {
    json!({
        "timestamp": time(t),
        "level": level as u8,
        "message": message,
        "name": name,
        "file": "",
        "line": 0,
    })
}

/// A `foxglove.RobotDescription` holding the URDF itself.
pub fn robot_description(urdf: &str) -> Value {
    json!({
        "url": "",
        "format": "urdf",
        "data": base64::engine::general_purpose::STANDARD.encode(urdf),
    })
}

/// The workspace as a `foxglove.SceneUpdate`: the bounds' twelve edges as a line list, the
/// exclusion boxes as translucent red cubes. Its lifetime is forever (0).
pub fn workspace(t: f64, bounds: &[f64; 6], boxes: &[[f64; 6]]) -> Value {
    let [x0, x1, y0, y1, z0, z1] = *bounds;
    let corner = |i: usize| {
        json!({
            "x": if i & 1 == 0 { x0 } else { x1 },
            "y": if i & 2 == 0 { y0 } else { y1 },
            "z": if i & 4 == 0 { z0 } else { z1 },
        })
    };
    // The edges join corners that differ in one coordinate (one bit).
    let mut points = Vec::new();
    for i in 0..8usize {
        for bit in [1, 2, 4] {
            if i & bit == 0 {
                points.extend([corner(i), corner(i | bit)]);
            }
        }
    }
    let identity = json!({ "position": {"x": 0, "y": 0, "z": 0},
                           "orientation": {"x": 0, "y": 0, "z": 0, "w": 1} });
    let line = json!({
        "type": 2, // LINE_LIST
        "pose": identity,
        "thickness": 2.0,
        "scale_invariant": true,
        "points": points,
        "color": { "r": 0.3, "g": 0.6, "b": 1.0, "a": 1.0 },
        "colors": [],
        "indices": [],
    });
    let cubes: Vec<Value> = boxes
        .iter()
        .map(|[x0, x1, y0, y1, z0, z1]| {
            json!({
                "pose": { "position": {"x": 0.5 * (x0 + x1), "y": 0.5 * (y0 + y1), "z": 0.5 * (z0 + z1)},
                          "orientation": {"x": 0, "y": 0, "z": 0, "w": 1} },
                "size": { "x": x1 - x0, "y": y1 - y0, "z": z1 - z0 },
                "color": { "r": 0.85, "g": 0.1, "b": 0.1, "a": 0.35 },
            })
        })
        .collect();
    json!({
        "deletions": [],
        "entities": [
            entity(t, WORLD, "workspace", json!({ "lines": [line] })),
            entity(t, WORLD, "exclusion_boxes", json!({ "cubes": cubes })),
        ],
    })
}

/// A `foxglove.SceneEntity` `id` in frame `frame` that lives until replaced, with the shapes
/// of `shapes` (`{"cubes": [..], "spheres": [..], ..}`; the other kinds empty; a `metadata`
/// there is taken too). An entity in a
/// link's frame is frame-locked: the viewer moves it with `/tf`.
pub fn entity(t: f64, frame: &str, id: &str, shapes: Value) -> Value {
    let mut entity = json!({
        "timestamp": time(t), "frame_id": frame, "id": id,
        "lifetime": { "sec": 0, "nsec": 0 }, "frame_locked": frame != WORLD, "metadata": [],
        "arrows": [], "cubes": [], "spheres": [], "cylinders": [], "lines": [],
        "triangles": [], "texts": [], "models": [],
    });
    if let (Some(entity), Value::Object(shapes)) = (entity.as_object_mut(), shapes) {
        entity.extend(shapes);
    }
    entity
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::indexing_slicing)]
    use super::*;

    #[test]
    fn every_schema_is_json_titled_with_its_name() {
        for topic in Topic::ALL {
            let schema: Value = serde_json::from_str(&topic.schema()).unwrap();
            assert_eq!(schema["title"], topic.schema_name(), "{topic:?}");
            assert_eq!(schema["type"], "object");
        }
    }

    #[test]
    fn times_are_whole_nanoseconds() {
        assert_eq!(time(1.5), json!({"sec": 1, "nsec": 500_000_000}));
        assert_eq!(nanos(0.01944 * 3.0), 58_320_000);
        assert_eq!(nanos(-1.0), 0);
        assert_eq!(nanos(f64::NAN), 0);
    }

    #[test]
    fn the_workspace_has_twelve_edges_and_a_cube_per_box() {
        let scene = workspace(
            0.0,
            &[0.0, 1.0, 0.0, 2.0, 0.0, 3.0],
            &[[0.0, 0.2, 0.0, 0.4, 0.0, 0.6]],
        );
        let points = scene["entities"][0]["lines"][0]["points"]
            .as_array()
            .unwrap();
        assert_eq!(points.len(), 24);
        for pair in points.chunks(2) {
            let differing = ["x", "y", "z"]
                .iter()
                .filter(|k| pair[0][**k] != pair[1][**k])
                .count();
            assert_eq!(differing, 1);
        }
        let cube = &scene["entities"][1]["cubes"][0];
        assert_eq!(cube["size"], json!({"x": 0.2, "y": 0.4, "z": 0.6}));
    }
}
