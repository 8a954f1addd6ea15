//! A URDF of a robot file: the same frames as armgate's forward kinematics, so that any URDF
//! tool (Foxglove, RViz, a Python parser) shows the arm where the controller thinks it is.
//!
//! Links: `world` (the `[base]` reference), `base_link` (frame {0}), `link_1`..`link_n` (the
//! joint frames {i} of docs/robot-file.md), `tool` (the tool frame {T}) and one
//! `exclusion_box_k` per workspace box (fixed to `world`, where the workspace is expressed).
//! Joints: `joint_1`..`joint_n` (revolute or prismatic about z of frame {i}), fixed otherwise.
//!
//! A link transform `RotX(α) · TransX(a) · RotY(β) · RotZ(θ + q) · TransZ(d)` is the URDF joint
//! origin `RotX(α) · TransX(a) · RotY(β) · RotZ(θ) · TransZ(d)` followed by the joint motion
//! `RotZ(q)` (RotZ and TransZ commute); a prismatic joint moves along the same z. The origins
//! are written with every digit (Rust's shortest round-trip form).

use std::fmt::Write as _;

use armgate_core::config::{JointType, ValidRobot};
use armgate_core::math::Frame;
use nalgebra::{Rotation3, Translation3, Vector3};

use crate::body::{LinkCapsule, link_capsules};

/// The URDF name of joint `i` (counting from 0): `joint_1`.., as [`crate::scene`]'s joint
/// states name them.
pub fn joint_name(i: usize) -> String {
    format!("joint_{}", i + 1)
}

/// The URDF name of the link moved by joint `i` (counting from 0): frame {i+1}.
pub fn link_name(i: usize) -> String {
    format!("link_{}", i + 1)
}

/// The world link (the base frame's reference) and the tool link.
pub const WORLD: &str = "world";
/// Frame {0}.
pub const BASE: &str = "base_link";
/// The tool frame {T}.
pub const TOOL: &str = "tool";

/// The fixed part of joint `i`'s link transform (the joint frame at q = 0 in its parent's).
pub fn joint_origin(robot: &ValidRobot, i: usize) -> Option<Frame> {
    let j = robot.joints.get(i)?;
    Some(
        Frame::rotation(Vector3::x() * j.alpha)
            * Translation3::new(j.a, 0.0, 0.0)
            * Frame::rotation(Vector3::y() * j.beta)
            * Frame::rotation(Vector3::z() * j.theta)
            * Translation3::new(0.0, 0.0, j.d),
    )
}

/// The base frame {0} in the world (`[base]`; the identity without one).
pub fn base_origin(robot: &ValidRobot) -> Frame {
    let [roll, pitch, yaw] = robot.base.rpy;
    Frame::from_parts(
        Vector3::from(robot.base.xyz).into(),
        Rotation3::from_euler_angles(roll, pitch, yaw),
    )
}

/// The tool frame {T} in the last joint frame {n}: `DH(tool) · Trans(xyz) · RPY(rpy)`.
pub fn tool_origin(robot: &ValidRobot) -> Frame {
    let t = &robot.tool;
    let [roll, pitch, yaw] = t.rpy;
    armgate_core::math::dh(t.a, t.alpha, t.d, t.theta)
        * Frame::from_parts(
            Vector3::from(t.xyz).into(),
            Rotation3::from_euler_angles(roll, pitch, yaw),
        )
}

/// Roll, pitch, yaw of URDF's `rpy` (`Rz(yaw) · Ry(pitch) · Rx(roll)`, the robot file's own
/// convention), exact at gimbal lock (yaw 0 there).
pub fn rpy(rotation: &Rotation3<f64>) -> [f64; 3] {
    let m = rotation.matrix();
    let cos_pitch = m.m11.hypot(m.m21);
    let pitch = (-m.m31).atan2(cos_pitch);
    if cos_pitch > 1e-12 {
        [m.m32.atan2(m.m33), pitch, m.m21.atan2(m.m11)]
    } else {
        [(-m.m23).atan2(m.m22), pitch, 0.0]
    }
}

/// The `<origin>` element of a frame.
fn origin(frame: &Frame) -> String {
    let [x, y, z]: [f64; 3] = frame.translation.vector.into();
    let [r, p, w] = rpy(&frame.rotation);
    format!(r#"<origin xyz="{x} {y} {z}" rpy="{r} {p} {w}"/>"#)
}

/// Colours of the drawing: links, joint housings, exclusion boxes (translucent).
const MATERIALS: [(&str, [f64; 4]); 3] = [
    ("armgate_link", [0.75, 0.75, 0.78, 1.0]),
    ("armgate_joint", [0.2, 0.35, 0.6, 1.0]),
    ("armgate_exclusion", [0.85, 0.1, 0.1, 0.35]),
];

/// The URDF document of `robot`.
pub fn urdf(robot: &ValidRobot) -> String {
    let radius = link_radius(robot);
    let capsules = link_capsules(robot);
    let collisions = |link: usize| collisions(&capsules, link);
    let mut out = String::new();
    let _ = writeln!(out, r#"<?xml version="1.0"?>"#);
    let _ = writeln!(
        out,
        "<!-- armgate: {} (generated from its robot file by `armgate urdf`; docs/visualisation.md) -->",
        robot.name.as_str()
    );
    let _ = writeln!(out, r#"<robot name="{}">"#, robot.name.as_str());
    for (name, [r, g, b, a]) in MATERIALS {
        let _ = writeln!(
            out,
            r#"  <material name="{name}"><color rgba="{r} {g} {b} {a}"/></material>"#
        );
    }
    let n = robot.joints.len();
    // Each link is drawn from its frame's origin to the next joint's origin (the tool for the
    // last one): base_link towards joint 1, link_i towards joint i+1.
    let next_origin = |i: usize| {
        joint_origin(robot, i).map_or_else(
            || tool_origin(robot).translation.vector,
            |f| f.translation.vector,
        )
    };
    link(&mut out, WORLD, &[], &[]);
    link(
        &mut out,
        BASE,
        &segments(next_origin(0), radius),
        &collisions(0),
    );
    fixed(&mut out, "world_to_base", WORLD, BASE, &base_origin(robot));
    for i in 0..n {
        let parent = if i == 0 {
            BASE.to_owned()
        } else {
            link_name(i - 1)
        };
        let Some((joint, origin_frame)) = robot.joints.get(i).zip(joint_origin(robot, i)) else {
            continue;
        };
        let mut shapes = vec![housing(joint.kind, radius)];
        shapes.extend(segments(next_origin(i + 1), radius));
        link(&mut out, &link_name(i), &shapes, &collisions(i + 1));
        let kind = match joint.kind {
            JointType::Revolute => "revolute",
            JointType::Prismatic => "prismatic",
        };
        let _ = writeln!(
            out,
            r#"  <joint name="{}" type="{kind}">
    <parent link="{parent}"/>
    <child link="{}"/>
    {}
    <axis xyz="0 0 1"/>
    <limit lower="{}" upper="{}" velocity="{}" effort="0"/>
  </joint>"#,
            joint_name(i),
            link_name(i),
            origin(&origin_frame),
            joint.min,
            joint.max,
            joint.max_rate,
        );
    }
    link(&mut out, TOOL, &[], &[]);
    let last = if n == 0 {
        BASE.to_owned()
    } else {
        link_name(n - 1)
    };
    fixed(&mut out, "tool_joint", &last, TOOL, &tool_origin(robot));
    for (k, b) in robot.workspace.boxes.iter().enumerate() {
        let name = format!("exclusion_box_{}", k + 1);
        let [x0, x1, y0, y1, z0, z1] = *b;
        let size = Vector3::new(x1 - x0, y1 - y0, z1 - z0);
        let shape = Shape {
            origin: Frame::identity(),
            geometry: format!(r#"<box size="{} {} {}"/>"#, size.x, size.y, size.z),
            material: "armgate_exclusion",
        };
        link(&mut out, &name, &[shape], &[]);
        let centre = Frame::translation(0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.5 * (z0 + z1));
        fixed(&mut out, &format!("{name}_joint"), WORLD, &name, &centre);
    }
    out.push_str("</robot>\n");
    out
}

/// One visual of a link.
struct Shape {
    origin: Frame,
    geometry: String,
    material: &'static str,
}

/// One `<collision>` of a link: a part of one of the body's capsules.
struct Collision {
    name: String,
    origin: Frame,
    geometry: String,
}

fn link(out: &mut String, name: &str, shapes: &[Shape], collisions: &[Collision]) {
    if shapes.is_empty() && collisions.is_empty() {
        let _ = writeln!(out, r#"  <link name="{name}"/>"#);
        return;
    }
    let _ = writeln!(out, r#"  <link name="{name}">"#);
    for s in shapes {
        let _ = writeln!(
            out,
            r#"    <visual>{}<geometry>{}</geometry><material name="{}"/></visual>"#,
            origin(&s.origin),
            s.geometry,
            s.material
        );
    }
    for c in collisions {
        let _ = writeln!(
            out,
            r#"    <collision name="{}">{}<geometry>{}</geometry></collision>"#,
            c.name,
            origin(&c.origin),
            c.geometry
        );
    }
    let _ = writeln!(out, "  </link>");
}

fn fixed(out: &mut String, name: &str, parent: &str, child: &str, frame: &Frame) {
    let _ = writeln!(
        out,
        r#"  <joint name="{name}" type="fixed"><parent link="{parent}"/><child link="{child}"/>{}</joint>"#,
        origin(frame)
    );
}

/// The drawn radius of the links: 2.5 % of the arm's summed link lengths, within 1..5 cm.
fn link_radius(robot: &ValidRobot) -> f64 {
    let tool = tool_origin(robot).translation.vector.norm();
    let reach: f64 = robot
        .joints
        .iter()
        .map(|j| j.a.abs() + j.d.abs())
        .sum::<f64>()
        + tool;
    (0.025 * reach).clamp(0.01, 0.05)
}

/// A joint housing at the frame origin, along the joint axis: a cylinder for a revolute joint,
/// a square box for a prismatic one.
fn housing(kind: JointType, radius: f64) -> Shape {
    let geometry = match kind {
        JointType::Revolute => format!(
            r#"<cylinder radius="{}" length="{}"/>"#,
            1.4 * radius,
            3.0 * radius
        ),
        JointType::Prismatic => format!(r#"<box size="{0} {0} {1}"/>"#, 2.4 * radius, 3.0 * radius),
    };
    Shape {
        origin: Frame::identity(),
        geometry,
        material: "armgate_joint",
    }
}

/// Cylinders from the frame origin to `target` (a point in the frame): along x first (DH's
/// `a`), then the rest (DH's `d`), as the link transform moves.
fn segments(target: Vector3<f64>, radius: f64) -> Vec<Shape> {
    let corner = Vector3::new(target.x, 0.0, 0.0);
    [(Vector3::zeros(), corner), (corner, target)]
        .into_iter()
        .filter_map(|(from, to)| cylinder(from, to, radius))
        .collect()
}

/// A cylinder between two points (none if they nearly coincide).
fn cylinder(from: Vector3<f64>, to: Vector3<f64>, radius: f64) -> Option<Shape> {
    let (origin, length) = along(from, to)?;
    Some(Shape {
        origin,
        geometry: format!(r#"<cylinder radius="{radius}" length="{length}"/>"#),
        material: "armgate_link",
    })
}

/// The frame at the middle of two points whose z axis points from one to the other, and
/// their distance (none if they nearly coincide): where a URDF cylinder between them sits.
pub fn along(from: Vector3<f64>, to: Vector3<f64>) -> Option<(Frame, f64)> {
    let axis = to - from;
    let length = axis.norm();
    if length < 1e-6 {
        return None;
    }
    let rotation = Rotation3::rotation_between(&Vector3::z(), &axis)
        .unwrap_or_else(|| Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI));
    Some((
        Frame::from_parts((0.5 * (from + to)).into(), rotation),
        length,
    ))
}

/// The collision geometry of link `link` (0 = base): each of the body's capsules on it
/// (`capsule_K`, K counting all the body's capsules from 1 in core's order) as URDF's core
/// spec can say it, a cylinder between the axis' ends (`capsule_K`, left out for a sphere)
/// and a sphere at each end (`capsule_K_a`, `capsule_K_b`).
fn collisions(capsules: &[LinkCapsule], link: usize) -> Vec<Collision> {
    let mut out = Vec::new();
    for (k, c) in capsules.iter().enumerate() {
        if usize::from(c.link) != link {
            continue;
        }
        let (name, r) = (format!("capsule_{}", k + 1), c.radius);
        if let Some((origin, length)) = along(c.a, c.b) {
            out.push(Collision {
                name: name.clone(),
                origin,
                geometry: format!(r#"<cylinder radius="{r}" length="{length}"/>"#),
            });
        }
        for (end, point) in [("a", c.a), ("b", c.b)] {
            out.push(Collision {
                name: format!("{name}_{end}"),
                origin: Frame::translation(point.x, point.y, point.z),
                geometry: format!(r#"<sphere radius="{r}"/>"#),
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::indexing_slicing)]
    use super::*;
    use crate::test_robots::robots;
    use armgate_core::kinematics::Chain;
    use armgate_core::rng::SplitMix64;

    #[test]
    fn rpy_round_trips_including_gimbal_lock() {
        let mut rng = SplitMix64::new(7);
        let half = std::f64::consts::FRAC_PI_2;
        let mut cases: Vec<[f64; 3]> = (0..1000)
            .map(|_| {
                [
                    rng.uniform(-3.1, 3.1),
                    rng.uniform(-1.5, 1.5),
                    rng.uniform(-3.1, 3.1),
                ]
            })
            .collect();
        cases.extend([[0.3, half, -0.2], [0.3, -half, 0.7], [0.0, 0.0, 0.0]]);
        for [r, p, y] in cases {
            let rot = Rotation3::from_euler_angles(r, p, y);
            let [r2, p2, y2] = rpy(&rot);
            let back = Rotation3::from_euler_angles(r2, p2, y2);
            assert!((back.matrix() - rot.matrix()).amax() < 1e-14, "{r} {p} {y}");
        }
    }

    /// The frames the URDF's origins compose (in Rust, the same arithmetic a URDF reader does)
    /// are armgate's FK; the Python test checks the written file with an independent parser.
    #[test]
    fn composed_origins_are_the_chain_frames() {
        for robot in robots() {
            let chain = Chain::new(&robot);
            let mut rng = SplitMix64::new(1);
            for _ in 0..100 {
                let q = chain.random_joints(&mut rng);
                let mut links = [Frame::identity(); armgate_core::MAX_JOINTS];
                let tool = chain.link_frames(&q, &mut links).unwrap();
                let mut frame = base_origin(&robot);
                for (i, (joint, qi)) in robot.joints.iter().zip(q.iter()).enumerate() {
                    let motion = match joint.kind {
                        JointType::Revolute => Frame::rotation(Vector3::z() * *qi),
                        JointType::Prismatic => Frame::translation(0.0, 0.0, *qi),
                    };
                    frame = frame * joint_origin(&robot, i).unwrap() * motion;
                    let err = frame.to_homogeneous() - links[i].to_homogeneous();
                    assert!(err.amax() < 1e-12, "{} link {i}", robot.name.as_str());
                }
                frame *= tool_origin(&robot);
                let err = frame.to_homogeneous() - tool.to_homogeneous();
                assert!(err.amax() < 1e-12, "{} tool", robot.name.as_str());
            }
        }
    }

    #[test]
    fn every_robot_has_its_links_joints_and_boxes() {
        for robot in robots() {
            let text = urdf(&robot);
            let n = robot.joints.len();
            assert!(text.contains(&format!(r#"<joint name="joint_{n}" type="#)));
            assert!(!text.contains(&format!(r#"name="joint_{}""#, n + 1)));
            assert_eq!(
                text.matches("exclusion_box_").count(),
                3 * robot.workspace.boxes.len(),
                "link, joint and child per box"
            );
            assert!(!text.contains("NaN") && !text.contains("inf"));
        }
    }
}
