//! What a recording shows, made from what a controller sees: joints, datagrams, CAN frames.
//!
//! Runs on the recorder's thread, never on the control loop: the FK of every link, the goal
//! bookkeeping and the JSON all cost their time here.

use std::net::SocketAddr;

use armgate_core::MAX_JOINTS;
use armgate_core::config::ValidRobot;
use armgate_core::kinematics::{Chain, Joints};
use armgate_core::math::Frame;
use armgate_protocol::can::CanFrame;
use armgate_protocol::client::banks::{WRITE_JOINTS, is_bank_2};
use armgate_protocol::client::{Command, MESSAGE_LEN, Message as Wire, Request, Severity, Text};
use nalgebra::{UnitQuaternion, Vector3};
use serde_json::{Value, json};

use crate::body_scene::BodyView;
use crate::foxglove::{self, Level, Topic};
use crate::urdf;

/// The longest datagram kept whole (the protocol's are 31 bytes).
pub const MAX_DATAGRAM: usize = 64;

/// Poses in a planned path.
const PATH_POSES: usize = 50;

/// Something the controller saw or did, stamped with its time (s; the simulation's, or the
/// recording client's clock).
// Not boxed: the recorder's queue holds events by value in slots allocated once, so that
// recording allocates nothing on the control loop.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
pub enum Event {
    /// The joints of one tick.
    Joints {
        /// Time (s).
        t: f64,
        /// Measured joints.
        measured: Joints,
        /// The joint command sent (none while off).
        command: Option<Joints>,
        /// The Cartesian set-point (Cartesian mode).
        setpoint: Option<Frame>,
        /// The measured tool pose as the controller reports it.
        pose: Option<Frame>,
    },
    /// A line for the log that is no datagram (e.g. the status a recording client read).
    Log {
        /// Time (s).
        t: f64,
        /// Its level.
        level: Level,
        /// Who says it.
        name: String,
        /// What.
        text: String,
    },
    /// A datagram from a client to the controller.
    Request {
        /// Time (s).
        t: f64,
        /// Sender.
        from: SocketAddr,
        /// Receiver (the controller).
        to: SocketAddr,
        /// Bytes used in `bytes`.
        len: usize,
        /// The datagram (cut at [`MAX_DATAGRAM`]).
        bytes: [u8; MAX_DATAGRAM],
    },
    /// A reply or notice from the controller.
    Answer {
        /// Time (s).
        t: f64,
        /// Sender (the controller).
        from: SocketAddr,
        /// Receiver.
        to: SocketAddr,
        /// The datagram.
        bytes: [u8; MESSAGE_LEN],
    },
    /// A CAN frame sent or received by the controller.
    Can {
        /// Time (s).
        t: f64,
        /// The frame.
        frame: CanFrame,
    },
}

/// One message for one channel.
#[derive(Clone, Debug)]
pub struct Message {
    /// Its channel.
    pub topic: Topic,
    /// Log time (ns).
    pub log_time: u64,
    /// JSON.
    pub data: Vec<u8>,
}

impl Message {
    fn new(topic: Topic, t: f64, value: &Value) -> Self {
        Self {
            topic,
            log_time: foxglove::nanos(t),
            data: value.to_string().into_bytes(),
        }
    }
}

/// Turns events into messages; remembers the goals a begin request starts.
pub struct Translator {
    robot: ValidRobot,
    chain: Chain,
    names: Vec<String>,
    /// The stored Cartesian goal (`GL`, `GT`).
    cartesian_goal: Option<Frame>,
    /// The stored joint goal (`jG`; bank 2 holds joints 7..).
    joint_goal: [f64; MAX_JOINTS],
    /// The last measured joints and their tool pose.
    last: Option<(Joints, Frame)>,
    /// The body's capsules and what `/body` shows.
    body: BodyView,
}

impl Translator {
    /// A translator for `robot`.
    pub fn new(robot: &ValidRobot) -> Self {
        let chain = Chain::new(robot);
        Self {
            robot: robot.clone(),
            names: (0..chain.dof()).map(urdf::joint_name).collect(),
            chain,
            cartesian_goal: None,
            joint_goal: [0.0; MAX_JOINTS],
            last: None,
            body: BodyView::new(robot),
        }
    }

    /// The robot.
    pub fn robot(&self) -> &ValidRobot {
        &self.robot
    }

    /// What a viewer needs before the first tick: the URDF and the workspace (at time `t`).
    pub fn preamble(&self, t: f64) -> Vec<Message> {
        let workspace = &self.robot.workspace;
        let body = self.body.preamble(t);
        let mut out = vec![
            Message::new(
                Topic::RobotDescription,
                t,
                &foxglove::robot_description(&urdf::urdf(&self.robot)),
            ),
            Message::new(
                Topic::Workspace,
                t,
                &foxglove::workspace(t, &workspace.bounds, &workspace.boxes),
            ),
        ];
        out.extend(body.map(|body| Message::new(Topic::Body, t, &body)));
        out
    }

    /// The messages of one event.
    pub fn translate(&mut self, event: &Event) -> Vec<Message> {
        match event {
            Event::Joints {
                t,
                measured,
                command,
                setpoint,
                pose,
            } => {
                let mut out = self.joints(*t, measured, command.as_ref(), setpoint.as_ref());
                if let Some(pose) = pose {
                    out.push(Message::new(
                        Topic::ToolPose,
                        *t,
                        &foxglove::pose_in_frame(*t, pose),
                    ));
                }
                out
            }
            Event::Log {
                t,
                level,
                name,
                text,
            } => vec![Message::new(
                Topic::Log,
                *t,
                &foxglove::log(*t, *level, name, text),
            )],
            Event::Request {
                t,
                from,
                to,
                len,
                bytes,
            } => self.request(*t, *from, *to, bytes.get(..*len).unwrap_or_default()),
            Event::Answer { t, from, to, bytes } => self.answer(*t, *from, *to, bytes),
            Event::Can { t, frame } => vec![Message::new(
                Topic::Can,
                *t,
                &json!({ "timestamp": foxglove::time(*t), "id": frame.id(), "hex": hex(frame.data()) }),
            )],
        }
    }

    fn joints(
        &mut self,
        t: f64,
        measured: &Joints,
        command: Option<&Joints>,
        setpoint: Option<&Frame>,
    ) -> Vec<Message> {
        let mut out = vec![Message::new(
            Topic::JointStates,
            t,
            &foxglove::joint_states(t, &self.names, measured),
        )];
        if let Some(command) = command {
            out.push(Message::new(
                Topic::JointCommand,
                t,
                &foxglove::joint_states(t, &self.names, command),
            ));
        }
        let mut links = [Frame::identity(); MAX_JOINTS];
        if let Ok(tool) = self.chain.link_frames(measured, &mut links) {
            let n = self.chain.dof();
            let base = urdf::base_origin(&self.robot);
            let mut names: Vec<String> = vec![urdf::BASE.to_owned()];
            let mut frames = vec![base];
            names.extend((0..n).map(urdf::link_name));
            frames.extend(links.iter().take(n).copied());
            names.push(urdf::TOOL.to_owned());
            frames.push(tool);
            let mut tree: Vec<(&str, &str, Frame)> = vec![(urdf::WORLD, urdf::BASE, base)];
            for k in 1..frames.len() {
                if let (Some(parent), Some(child), Some(pf), Some(cf)) = (
                    names.get(k - 1),
                    names.get(k),
                    frames.get(k - 1),
                    frames.get(k),
                ) {
                    tree.push((parent, child, pf.inverse() * cf));
                }
            }
            out.push(Message::new(
                Topic::Transforms,
                t,
                &foxglove::frame_transforms(t, &tree),
            ));
            self.last = Some((*measured, tool));
        }
        if let Some((clearance, scene)) = self.body.update(t, measured) {
            out.push(Message::new(Topic::Clearance, t, &clearance));
            out.extend(scene.map(|scene| Message::new(Topic::Body, t, &scene)));
        }
        if let Some(setpoint) = setpoint {
            out.push(Message::new(
                Topic::Setpoint,
                t,
                &foxglove::pose_in_frame(t, setpoint),
            ));
        }
        out
    }

    fn request(&mut self, t: f64, from: SocketAddr, to: SocketAddr, bytes: &[u8]) -> Vec<Message> {
        let request = Wire::new_checked(bytes)
            .ok()
            .and_then(|m| Request::parse(&m).ok());
        let text = match request {
            Some(request) => {
                self.remember_goal(&request);
                describe(request.command.chars(), &request.values, request.index)
            }
            None => format!("undecodable {} bytes: {}", bytes.len(), hex(bytes)),
        };
        vec![
            datagram(t, from, to, bytes),
            Message::new(
                Topic::Log,
                t,
                &foxglove::log(t, Level::Info, &from.to_string(), &text),
            ),
        ]
    }

    fn answer(
        &mut self,
        t: f64,
        from: SocketAddr,
        to: SocketAddr,
        bytes: &[u8; MESSAGE_LEN],
    ) -> Vec<Message> {
        let mut out = vec![datagram(t, from, to, bytes)];
        let Ok(message) = Wire::new_checked(&bytes[..]) else {
            return out;
        };
        let (level, text) = match Text::parse(&message) {
            Ok(text) if text.severity() == Severity::Error => {
                (Level::Error, text.as_str().to_owned())
            }
            Ok(text) => (Level::Warning, text.as_str().to_owned()),
            Err(_) => (
                Level::Info,
                describe(message.command(), &message.values(), message.index()),
            ),
        };
        out.push(Message::new(
            Topic::Log,
            t,
            &foxglove::log(t, level, &from.to_string(), &text),
        ));
        // A begin that was accepted (its reply, not an ER text): the move to the stored goal.
        match Command::from_reply_chars(message.command()) {
            Some(Command::Begin) if level == Level::Info => out.extend(self.cartesian_plan(t)),
            Some(Command::JointBegin) if level == Level::Info => out.extend(self.joint_plan(t)),
            _ => {}
        }
        out
    }

    fn remember_goal(&mut self, request: &Request) {
        let v = request.values.map(f64::from);
        match request.command {
            Command::GoalQuaternion => {
                let q = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                    v[6], v[3], v[4], v[5],
                ));
                self.cartesian_goal = Some(Frame::from_parts(
                    Vector3::new(v[0], v[1], v[2]).into(),
                    q.into(),
                ));
            }
            Command::GoalRpy => {
                let rotation = nalgebra::Rotation3::from_euler_angles(v[3], v[4], v[5]);
                self.cartesian_goal = Some(Frame::from_parts(
                    Vector3::new(v[0], v[1], v[2]).into(),
                    rotation,
                ));
            }
            Command::JointGoal => {
                let first = if is_bank_2(request.index) {
                    WRITE_JOINTS
                } else {
                    0
                };
                for (slot, value) in self
                    .joint_goal
                    .iter_mut()
                    .skip(first)
                    .zip(&v)
                    .take(WRITE_JOINTS)
                {
                    *slot = *value;
                }
            }
            _ => {}
        }
    }

    /// The goal and a straight tool line to it from the last measured pose.
    fn cartesian_plan(&self, t: f64) -> Vec<Message> {
        let (Some(goal), Some((_, start))) = (self.cartesian_goal, self.last) else {
            return Vec::new();
        };
        let path: Vec<Frame> = (0..=PATH_POSES)
            .map(|k| start.lerp_slerp(&goal, k as f64 / PATH_POSES as f64))
            .collect();
        plan(t, &goal, &path)
    }

    /// The tool pose at the joint goal, and the FK of the straight joint-space line to it
    /// (the joint generator moves all joints in step).
    fn joint_plan(&self, t: f64) -> Vec<Message> {
        let Some((start, _)) = self.last else {
            return Vec::new();
        };
        let n = self.chain.dof();
        let mut goal = start;
        for (g, value) in goal.iter_mut().zip(&self.joint_goal).take(n) {
            *g = *value;
        }
        let path: Vec<Frame> = (0..=PATH_POSES)
            .filter_map(|k| {
                let s = k as f64 / PATH_POSES as f64;
                let mut q = start;
                for (v, (a, b)) in q.iter_mut().zip(start.iter().zip(goal.iter())) {
                    *v = a + s * (b - a);
                }
                self.chain.forward(&q).ok()
            })
            .collect();
        match self.chain.forward(&goal) {
            Ok(goal_pose) => plan(t, &goal_pose, &path),
            Err(_) => Vec::new(),
        }
    }
}

fn plan(t: f64, goal: &Frame, path: &[Frame]) -> Vec<Message> {
    vec![
        Message::new(Topic::Goal, t, &foxglove::pose_in_frame(t, goal)),
        Message::new(Topic::PlannedPath, t, &foxglove::poses_in_frame(t, path)),
    ]
}

fn datagram(t: f64, from: SocketAddr, to: SocketAddr, bytes: &[u8]) -> Message {
    Message::new(
        Topic::Udp,
        t,
        &json!({ "timestamp": foxglove::time(t), "from": from.to_string(), "to": to.to_string(), "hex": hex(bytes) }),
    )
}

/// `GT 0.25 -0.125 1 0 0.5 0 2.5 #0`: the characters, the seven floats and the index.
fn describe(chars: [u8; 2], values: &[f32], index: u8) -> String {
    let chars: String = chars
        .iter()
        .map(|b| {
            if b.is_ascii_graphic() {
                char::from(*b)
            } else {
                '?'
            }
        })
        .collect();
    let values: Vec<String> = values.iter().map(ToString::to_string).collect();
    format!("{chars} {} #{index}", values.join(" "))
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::approx_constant)]
    use super::*;
    use armgate_protocol::client::{Reply, Severity};

    fn robot() -> ValidRobot {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../robots/ranger-mk1.toml");
        armgate_core::config::load_file(std::path::Path::new(path)).unwrap()
    }

    const CLIENT: &str = "127.0.0.1:5000";
    const CONTROLLER: &str = "127.0.0.1:7031";

    fn request(command: Command, values: [f32; 7]) -> Event {
        let bytes = Request {
            command,
            values,
            index: 0,
        }
        .to_bytes();
        let mut padded = [0; MAX_DATAGRAM];
        padded[..MESSAGE_LEN].copy_from_slice(&bytes);
        Event::Request {
            t: 1.0,
            from: CLIENT.parse().unwrap(),
            to: CONTROLLER.parse().unwrap(),
            len: MESSAGE_LEN,
            bytes: padded,
        }
    }

    fn answer(bytes: [u8; MESSAGE_LEN]) -> Event {
        Event::Answer {
            t: 1.0,
            from: CONTROLLER.parse().unwrap(),
            to: CLIENT.parse().unwrap(),
            bytes,
        }
    }

    fn topics(messages: &[Message]) -> Vec<Topic> {
        messages.iter().map(|m| m.topic).collect()
    }

    fn json_of(message: &Message) -> Value {
        serde_json::from_slice(&message.data).unwrap()
    }

    #[test]
    fn an_accepted_begin_draws_the_stored_goal_and_a_refused_one_nothing() {
        let robot = robot();
        let mut translator = Translator::new(&robot);
        let home = robot.home();
        let joints = Event::Joints {
            t: 0.0,
            measured: home,
            command: None,
            setpoint: None,
            pose: None,
        };
        assert_eq!(
            topics(&translator.translate(&joints)),
            [
                Topic::JointStates,
                Topic::Transforms,
                Topic::Clearance,
                Topic::Body
            ]
        );
        let goal = [0.0, 0.3, 0.8, 0.0, 1.5708, 0.0, 3.0];
        let logged = translator.translate(&request(Command::GoalRpy, goal));
        assert_eq!(topics(&logged), [Topic::Udp, Topic::Log]);
        assert_eq!(
            json_of(&logged[1])["message"],
            "GT 0 0.3 0.8 0 1.5708 0 3 #0"
        );
        // Refused: an ER text, logged as an error, no goal.
        let refusal = Text::new(Severity::Error, 20, "Cmd BG rejected");
        let mut bytes = [0; MESSAGE_LEN];
        refusal.emit(&mut Wire::new_checked(&mut bytes[..]).unwrap());
        let refused = translator.translate(&answer(bytes));
        assert_eq!(topics(&refused), [Topic::Udp, Topic::Log]);
        assert_eq!(json_of(&refused[1])["level"], Level::Error as u8);
        // Accepted: the goal and a straight line to it from the measured tool pose.
        let accepted = translator.translate(&answer(Reply::null(Command::Begin).to_bytes()));
        assert_eq!(
            topics(&accepted),
            [Topic::Udp, Topic::Log, Topic::Goal, Topic::PlannedPath]
        );
        let position = &json_of(&accepted[2])["pose"]["position"];
        assert!((position["y"].as_f64().unwrap() - 0.3).abs() < 1e-6);
        let path = json_of(&accepted[3]);
        let poses = path["poses"].as_array().unwrap();
        assert_eq!(poses.len(), PATH_POSES + 1);
        let start = Chain::new(&robot)
            .forward(&home)
            .unwrap()
            .translation
            .vector;
        let first = &poses[0]["position"];
        assert!((first["z"].as_f64().unwrap() - start.z).abs() < 1e-12);
        assert_eq!(poses[PATH_POSES]["position"], *position);
    }

    #[test]
    fn a_joint_begin_draws_the_fk_of_the_joint_goal() {
        let robot = robot();
        let chain = Chain::new(&robot);
        let mut translator = Translator::new(&robot);
        let home = robot.home();
        translator.translate(&Event::Joints {
            t: 0.0,
            measured: home,
            command: None,
            setpoint: None,
            pose: None,
        });
        let goal = [1.5708_f32, 0.1, 1.5, 0.0, 1.2, 0.0, 0.0];
        translator.translate(&request(Command::JointGoal, goal));
        let accepted = translator.translate(&answer(Reply::null(Command::JointBegin).to_bytes()));
        assert_eq!(topics(&accepted)[2..], [Topic::Goal, Topic::PlannedPath]);
        let q: Vec<f64> = goal[..6].iter().map(|v| f64::from(*v)).collect();
        let expected = chain.forward(&q).unwrap().translation.vector;
        let got = &json_of(&accepted[2])["pose"]["position"];
        assert!((got["x"].as_f64().unwrap() - expected.x).abs() < 1e-12);
        assert!((got["z"].as_f64().unwrap() - expected.z).abs() < 1e-12);
    }
}
