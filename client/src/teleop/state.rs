//! The keyboard client's state and its key handling, free of any terminal or socket.
//!
//! The desired pose and joints follow the measured ones unless the keys changed them
//! ([`Edit`]). An edit is dropped, and the desired values follow again, whenever the arm moves
//! for a reason other than this client's own motion: another client, a mode switch, a motion
//! that ended. So a key press always changes the measured state by one step and nothing else.

use std::time::{Duration, Instant};

use super::jog::{BASE_JOG_RATE, BASE_JOG_SPEED, FIRST_HOLD};
use crate::status::{Motion, Status};
use crate::{Mode, Pose, Text, TwistFrame, Velocity, next_mode};
use armgate_protocol::client::{Notice, Rejection};

/// The base Cartesian step per key press (m), multiplied by the scale.
pub const BASE_STEP: f64 = 0.001;

/// The base joint step per key press (rad, or m for prismatic joints), multiplied by the scale.
pub const BASE_JOINT_STEP: f64 = 0.01;

/// The smallest and largest scale.
pub const SCALE_RANGE: (f64, f64) = (1.0 / 64.0, 1024.0);

/// Readings older than this are shown as stale.
pub const STALE: Duration = Duration::from_secs(1);

/// An ER/WN line is shown this long.
pub const TEXT_SHOWN: Duration = Duration::from_secs(10);

/// A change of the measured position beyond this (m) is a motion.
const MOVED: f64 = 0.0005;

/// A change of the measured orientation or of a joint beyond this (rad) is a motion.
const MOVED_ANGLE: f64 = 0.001;

/// Without the status request: the own motion has ended after this many polls without motion.
const STILL_POLLS: u32 = 5;

/// A change below this (m or rad) is no motion at all.
const STILL: f64 = 1e-5;

/// Whose the desired values are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Edit {
    /// Nobody's: they follow the measured values.
    Following,
    /// Changed by the keys, not sent yet.
    Unsent,
    /// Sent: this client's motion goes there.
    Sent,
}

/// A key, as the teleop understands it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Key {
    /// ←
    Left,
    /// →
    Right,
    /// ↑
    Up,
    /// ↓
    Down,
    /// Page Up
    PageUp,
    /// Page Down
    PageDown,
    /// Enter
    Enter,
    /// Esc
    Esc,
    /// A character (`+`, `-`, space, `j`, `m`, `q`, digits).
    Char(char),
}

/// What the keys move.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variant {
    /// The tool's x, y, z (GT + BG).
    Cartesian,
    /// One joint at a time (jG + jB).
    Joint,
}

/// A request sequence the I/O side should perform.
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    /// GT (position, roll/pitch/yaw, T = 0) then BG; if BG is refused, ST and BG once more.
    MoveCartesian {
        /// Position (m).
        xyz: [f64; 3],
        /// Roll, pitch, yaw (rad).
        rpy: [f64; 3],
    },
    /// jG then jB; if jB is refused, ST and jB once more.
    MoveJoints(Vec<f64>),
    /// CM.
    SetMode(Mode),
    /// Stream TW (Cartesian keys) or jW (joint keys) while the key is held.
    Jog(Velocity),
    /// ST: stop every motion.
    Stop,
    /// ON: start the drives (clears a drive fault).
    DrivesOn,
}

/// What the I/O side reports.
#[derive(Clone, Debug, PartialEq)]
pub enum Event {
    /// A PS reply.
    Pose(Pose),
    /// A jP reply (all joints).
    Joints(Vec<f64>),
    /// A TM reply (all joints).
    Temperatures(Vec<f64>),
    /// An ER/WN text: an unsolicited notice or a refusal.
    Text(Text),
    /// The mode the controller reported after CM.
    Mode(Mode),
    /// A CM failed (the failure itself comes as a text or status).
    ModeFailed,
    /// What was sent, or what failed locally (e.g. a timeout).
    Status(String),
    /// The controller's state (SQ).
    Controller(Status),
    /// A motion request was accepted: this client's motion runs.
    Started(String),
    /// A motion request was refused (the reason is the text).
    Refused(Text),
    /// A poll had no answer (the reason is the text).
    NoReply(String),
}

/// Everything the screen shows.
#[derive(Clone, Debug, PartialEq)]
pub struct TeleopState {
    /// The controller's address, for the title.
    pub addr: String,
    /// Cartesian or joint keys.
    pub variant: Variant,
    /// Send on every key press (else on Enter).
    pub live: bool,
    /// Keys stream velocities while held (`TW`/`jW`) instead of editing the desired values.
    pub jog: bool,
    /// The arm's number of joints.
    pub joint_count: usize,
    /// The last PS reply.
    pub current: Option<Pose>,
    /// The pose the keys edit; initialised from the first PS reply.
    pub desired: Option<Pose>,
    /// The last jP reply.
    pub joints: Vec<f64>,
    /// The joints the keys edit; initialised from the first jP reply.
    pub desired_joints: Vec<f64>,
    /// The last TM reply.
    pub temperatures: Vec<f64>,
    /// The step multiplier.
    pub scale: f64,
    /// The joint the joint keys edit (0-based).
    pub selected: usize,
    /// The mode the controller last reported (unknown until a CM).
    pub mode: Option<Mode>,
    /// The mode of a CM sent but not answered yet; `m` cycles on from it.
    pub mode_pending: Option<Mode>,
    /// The latest ER/WN text.
    pub last_text: Option<Text>,
    /// When it came.
    pub text_at: Option<Instant>,
    /// The latest status line.
    pub status: String,
    /// Set by q / Esc.
    pub quit: bool,
    /// Whose the desired pose is.
    pub pose_edit: Edit,
    /// Whose the desired joints are.
    pub joints_edit: Edit,
    /// A motion this client started is running.
    pub own_motion: bool,
    /// The controller's last status (none from a controller without SQ).
    pub controller: Option<Status>,
    /// The last move request was refused with this text: the desired values are not reachable.
    pub refused: Option<Text>,
    /// The time of the last reading (PS).
    pub read_at: Option<Instant>,
    /// The last poll got no answer.
    pub no_reply: bool,
    /// The clock the state is drawn at (set with [`at`](Self::at)).
    pub now: Instant,
    /// Polls without motion, while the own motion runs (without SQ).
    still_polls: u32,
    /// The last jog key and when it came (a press or an auto-repeat).
    last_jog: Option<(Key, Instant)>,
    /// The jog key held when the stop key was pressed, and when it last repeated: its repeats
    /// do not jog again, only a new press does (after a pause longer than [`FIRST_HOLD`]).
    held_at_stop: Option<(Key, Instant)>,
}

impl TeleopState {
    /// The state before any reply.
    pub fn new(addr: impl Into<String>, joint_count: usize, live: bool) -> Self {
        Self {
            addr: addr.into(),
            variant: Variant::Cartesian,
            live,
            jog: false,
            joint_count,
            current: None,
            desired: None,
            joints: Vec::new(),
            desired_joints: Vec::new(),
            temperatures: Vec::new(),
            scale: 1.0,
            selected: 0,
            mode: None,
            mode_pending: None,
            last_text: None,
            text_at: None,
            status: String::from("waiting for the controller"),
            quit: false,
            pose_edit: Edit::Following,
            joints_edit: Edit::Following,
            own_motion: false,
            controller: None,
            refused: None,
            read_at: None,
            no_reply: false,
            now: Instant::now(),
            still_polls: 0,
            last_jog: None,
            held_at_stop: None,
        }
    }

    /// Sets the clock: what is stale and which texts have expired is judged at `now`.
    pub fn at(&mut self, now: Instant) {
        self.now = now;
    }

    /// How old the readings are, if they are stale (or never came).
    pub fn stale(&self) -> Option<Option<Duration>> {
        match self.read_at {
            None => Some(None),
            Some(t) => {
                let age = self.now.saturating_duration_since(t);
                (age > STALE || self.no_reply).then_some(Some(age))
            }
        }
    }

    /// The ER/WN text, while it is recent.
    pub fn recent_text(&self) -> Option<&Text> {
        match self.text_at {
            Some(t) if self.now.saturating_duration_since(t) < TEXT_SHOWN => {
                self.last_text.as_ref()
            }
            _ => None,
        }
    }

    /// This client's motion has ended: what it sent gives way to the measured values.
    fn motion_ended(&mut self) {
        self.own_motion = false;
        if self.pose_edit == Edit::Sent {
            self.pose_edit = Edit::Following;
            self.desired = self.current;
        }
        if self.joints_edit == Edit::Sent {
            self.joints_edit = Edit::Following;
            self.desired_joints.clone_from(&self.joints);
        }
    }

    /// The arm moved, or will, for a reason other than this client's motion: edits are void.
    fn moved_elsewhere(&mut self, why: &str) {
        if self.pose_edit != Edit::Following || self.joints_edit != Edit::Following {
            self.status = format!("{why}: desired <- current");
        }
        self.own_motion = false;
        self.pose_edit = Edit::Following;
        self.joints_edit = Edit::Following;
        self.desired = self.current;
        self.desired_joints.clone_from(&self.joints);
        self.refused = None;
    }

    fn pose_measured(&mut self, pose: Pose) {
        let change = |c: &Pose| (c.distance(&pose), c.angle_to(&pose));
        let (distance, angle) = self.current.as_ref().map_or((0.0, 0.0), change);
        let moved = distance > MOVED || angle > MOVED_ANGLE;
        let still = distance <= STILL && angle <= STILL;
        self.current = Some(pose);
        self.read_at = Some(self.now);
        self.no_reply = false;
        self.still_polls = if still { self.still_polls + 1 } else { 0 };
        if self.own_motion && self.controller.is_none() && self.still_polls >= STILL_POLLS {
            self.motion_ended();
        }
        if moved && !self.own_motion && self.pose_edit != Edit::Sent {
            self.moved_elsewhere("the arm moved");
        }
        if self.pose_edit == Edit::Following || self.desired.is_none() {
            self.desired = Some(pose);
        }
    }

    fn joints_measured(&mut self, q: Vec<f64>) {
        let moved = self.joints.len() == q.len()
            && self
                .joints
                .iter()
                .zip(&q)
                .any(|(a, b)| (a - b).abs() > MOVED_ANGLE);
        let follow = self.joints_edit == Edit::Following || self.desired_joints.len() != q.len();
        self.joints = q;
        if moved && !self.own_motion && self.joints_edit != Edit::Sent {
            self.moved_elsewhere("the arm moved");
        } else if follow {
            self.desired_joints.clone_from(&self.joints);
        }
    }

    fn controller_state(&mut self, status: Status) {
        let mode_changed = self.mode.is_some_and(|m| m != status.mode);
        self.mode = Some(status.mode);
        if self.own_motion && status.motion == Motion::Holding {
            self.motion_ended();
        } else if !self.own_motion && status.motion != Motion::Holding {
            self.moved_elsewhere("another motion runs");
        }
        if mode_changed {
            self.moved_elsewhere("the mode changed");
        }
        self.controller = Some(status);
    }

    /// The mode the keys need: Cartesian for the Cartesian keys, joint for the joint keys.
    pub fn keys_mode(&self) -> Mode {
        match self.variant {
            Variant::Cartesian => Mode::Cartesian,
            Variant::Joint => Mode::Joint,
        }
    }

    /// The Cartesian step (m).
    pub fn step(&self) -> f64 {
        BASE_STEP * self.scale
    }

    /// The joint step (rad).
    pub fn joint_step(&self) -> f64 {
        BASE_JOINT_STEP * self.scale
    }

    /// Takes in a report of the I/O side.
    pub fn apply(&mut self, event: Event) {
        match event {
            Event::Pose(pose) => {
                if self.current.is_none() {
                    self.status = String::from("connected");
                }
                self.pose_measured(pose);
            }
            Event::Joints(q) => self.joints_measured(q),
            Event::Temperatures(t) => self.temperatures = t,
            Event::Text(text) => self.show_text(text),
            Event::Mode(mode) => {
                let changed = self.mode != Some(mode);
                self.mode = Some(mode);
                self.mode_pending = None;
                if changed {
                    self.moved_elsewhere("the mode changed");
                }
                self.status = format!("mode {}", mode.name());
            }
            Event::ModeFailed => self.mode_pending = None,
            Event::Status(status) => self.status = status,
            Event::Controller(status) => self.controller_state(status),
            Event::Started(status) => {
                self.own_motion = true;
                self.still_polls = 0;
                self.refused = None;
                self.status = status;
            }
            Event::Refused(text) => {
                for edit in [&mut self.pose_edit, &mut self.joints_edit] {
                    if *edit == Edit::Sent {
                        *edit = Edit::Unsent;
                    }
                }
                self.refused = Some(text);
                self.show_text(text);
                if let Ok(Notice::Rejected(_, Rejection::NeedsMode(mode))) = Notice::parse(&text) {
                    self.status = format!("needs mode {}: press m", mode.name());
                }
            }
            Event::NoReply(status) => {
                self.no_reply = true;
                self.status = status;
            }
        }
    }

    fn show_text(&mut self, text: Text) {
        self.last_text = Some(text);
        self.text_at = Some(self.now);
    }

    /// Handles one key; returns the requests to send, if any.
    pub fn handle_key(&mut self, key: Key) -> Option<Action> {
        match key {
            Key::Esc | Key::Char('q') => {
                self.quit = true;
                None
            }
            Key::Char('+' | '=') => {
                self.scale = (self.scale * 2.0).min(SCALE_RANGE.1);
                None
            }
            Key::Char('-' | '_') => {
                self.scale = (self.scale / 2.0).max(SCALE_RANGE.0);
                None
            }
            Key::Char(' ') => {
                let now = self.now;
                self.held_at_stop = self
                    .last_jog
                    .filter(|(_, at)| now.saturating_duration_since(*at) <= FIRST_HOLD);
                self.status = String::from(if self.held_at_stop.is_some() {
                    "stop (ST): release the key, then press it again to move"
                } else {
                    "stop (ST)"
                });
                Some(Action::Stop)
            }
            Key::Char('o') => {
                self.status = String::from("drives on (ON)");
                Some(Action::DrivesOn)
            }
            Key::Char('c') => {
                self.desired = self.current;
                self.desired_joints.clone_from(&self.joints);
                self.pose_edit = Edit::Following;
                self.joints_edit = Edit::Following;
                self.refused = None;
                self.status = String::from("desired <- current");
                None
            }
            Key::Char('j') => {
                self.variant = match self.variant {
                    Variant::Cartesian => Variant::Joint,
                    Variant::Joint => Variant::Cartesian,
                };
                self.status = match self.variant {
                    Variant::Cartesian => "Cartesian keys (needs mode cartesian)",
                    Variant::Joint => "joint keys (needs mode joint)",
                }
                .to_owned();
                None
            }
            Key::Char('v') => {
                self.jog = !self.jog;
                self.status = String::from(if self.jog {
                    "jog: hold a key to move"
                } else {
                    "step: keys edit the desired values"
                });
                None
            }
            Key::Char('m') => {
                // The mode the keys need first (never through off); from there on the cycle.
                let present = self.mode_pending.or(self.mode);
                let needed = self.keys_mode();
                let next = if present == Some(needed) {
                    next_mode(needed)
                } else {
                    needed
                };
                self.mode_pending = Some(next);
                Some(Action::SetMode(next))
            }
            Key::Enter => self.send(),
            _ => match self.variant {
                Variant::Cartesian => self.cartesian_key(key),
                Variant::Joint => self.joint_key(key),
            },
        }
    }

    fn cartesian_key(&mut self, key: Key) -> Option<Action> {
        let (axis, sign) = match key {
            Key::Left => (0, -1.0),
            Key::Right => (0, 1.0),
            Key::Down => (1, -1.0),
            Key::Up => (1, 1.0),
            Key::PageDown => (2, -1.0),
            Key::PageUp => (2, 1.0),
            _ => return None,
        };
        if self.jog {
            let mut linear = [0.0; 3];
            if let Some(v) = linear.get_mut(axis) {
                *v = sign * BASE_JOG_SPEED * self.scale;
            }
            return self.jogging(
                key,
                Velocity::Twist {
                    linear,
                    angular: [0.0; 3],
                    frame: TwistFrame::Base,
                },
            );
        }
        let step = self.step();
        let Some(desired) = self.desired.as_mut() else {
            self.status = String::from("no pose from the controller yet");
            return None;
        };
        if let Some(v) = desired.xyz.get_mut(axis) {
            *v += sign * step;
        }
        self.pose_edit = Edit::Unsent;
        self.edited()
    }

    fn joint_key(&mut self, key: Key) -> Option<Action> {
        let sign = match key {
            Key::Left => -1.0,
            Key::Right => 1.0,
            Key::Up => {
                self.selected = self.selected.saturating_sub(1);
                return None;
            }
            Key::Down => {
                self.selected = (self.selected + 1).min(self.joint_count.saturating_sub(1));
                return None;
            }
            Key::Char(c @ '1'..='8') => {
                let k = usize::from(c as u8 - b'1');
                if k < self.joint_count {
                    self.selected = k;
                }
                return None;
            }
            _ => return None,
        };
        if self.jog {
            let mut rates = vec![0.0; self.joint_count];
            if let Some(r) = rates.get_mut(self.selected) {
                *r = sign * BASE_JOG_RATE * self.scale;
            }
            return self.jogging(key, Velocity::Joints(rates));
        }
        let step = self.joint_step();
        let Some(q) = self.desired_joints.get_mut(self.selected) else {
            self.status = String::from("no joints from the controller yet");
            return None;
        };
        *q += sign * step;
        self.joints_edit = Edit::Unsent;
        self.edited()
    }

    /// A jog by `key`: this client's motion, which the desired values follow — unless `key`
    /// is still held from before a stop (its auto-repeats keep coming).
    fn jogging(&mut self, key: Key, velocity: Velocity) -> Option<Action> {
        let now = self.now;
        if let Some((held, at)) = self.held_at_stop {
            if held == key && now.saturating_duration_since(at) <= FIRST_HOLD {
                self.held_at_stop = Some((held, now));
                self.status = String::from("stopped: release the key, then press it again to move");
                return None;
            }
            self.held_at_stop = None;
        }
        self.last_jog = Some((key, now));
        self.own_motion = true;
        self.still_polls = 0;
        self.pose_edit = Edit::Following;
        self.joints_edit = Edit::Following;
        self.refused = None;
        Some(Action::Jog(velocity))
    }

    /// After a change of the desired pose or joints: send at once when live.
    fn edited(&mut self) -> Option<Action> {
        if self.live { self.send() } else { None }
    }

    /// The requests that move to the desired pose or joints.
    fn send(&mut self) -> Option<Action> {
        match self.variant {
            Variant::Cartesian => {
                let (Some(desired), Some(current)) = (self.desired.as_mut(), self.current) else {
                    self.status = String::from("no pose from the controller yet");
                    return None;
                };
                // Keep the current orientation.
                desired.quaternion = current.quaternion;
                self.pose_edit = Edit::Sent;
                Some(Action::MoveCartesian {
                    xyz: desired.xyz,
                    rpy: current.rpy(),
                })
            }
            Variant::Joint => {
                if self.desired_joints.is_empty() {
                    self.status = String::from("no joints from the controller yet");
                    return None;
                }
                self.joints_edit = Edit::Sent;
                Some(Action::MoveJoints(self.desired_joints.clone()))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Quaternion;

    fn pose(x: f64, y: f64, z: f64) -> Pose {
        Pose {
            xyz: [x, y, z],
            quaternion: Quaternion::IDENTITY,
        }
    }

    fn ready(live: bool) -> TeleopState {
        let mut s = TeleopState::new("127.0.0.1:7031", 8, live);
        s.apply(Event::Pose(pose(0.5, 0.2, 0.1)));
        s.apply(Event::Joints(vec![0.0; 8]));
        s
    }

    fn close(a: [f64; 3], b: [f64; 3]) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12)
    }

    #[test]
    fn untouched_desired_values_follow_the_measured_ones() {
        let mut s = TeleopState::new("a", 6, false);
        assert_eq!(s.handle_key(Key::Right), None);
        assert_eq!(s.status, "no pose from the controller yet");
        s.apply(Event::Pose(pose(0.5, 0.2, 0.1)));
        assert_eq!(s.desired, Some(pose(0.5, 0.2, 0.1)));
        s.apply(Event::Pose(pose(0.6, 0.2, 0.1)));
        assert_eq!(s.desired, Some(pose(0.6, 0.2, 0.1)));
        s.apply(Event::Joints(vec![1.0; 6]));
        s.apply(Event::Joints(vec![2.0; 6]));
        assert_eq!(s.desired_joints, [2.0; 6]);
    }

    #[test]
    fn the_stop_key_holds_off_a_held_jog_key_until_it_is_pressed_again() {
        let mut s = ready(false);
        s.jog = true;
        let t0 = Instant::now();
        s.at(t0);
        assert!(matches!(s.handle_key(Key::Right), Some(Action::Jog(_))));
        s.at(t0 + Duration::from_millis(40));
        assert_eq!(s.handle_key(Key::Char(' ')), Some(Action::Stop));
        assert_eq!(
            s.status,
            "stop (ST): release the key, then press it again to move"
        );
        // The held key's repeats, 40 ms apart for a second: no jog.
        for k in 2..27 {
            s.at(t0 + Duration::from_millis(40 * k));
            assert_eq!(s.handle_key(Key::Right), None, "repeat {k}");
        }
        // Another key moves at once; so does the same key pressed after a pause.
        assert!(matches!(s.handle_key(Key::Up), Some(Action::Jog(_))));
        s.handle_key(Key::Char(' '));
        s.at(t0 + Duration::from_millis(40 * 27) + FIRST_HOLD * 2);
        assert!(matches!(s.handle_key(Key::Up), Some(Action::Jog(_))));
        // A stop with no key held lets the next press jog.
        s.at(t0 + Duration::from_secs(10));
        s.handle_key(Key::Char(' '));
        assert_eq!(s.status, "stop (ST)");
        assert!(matches!(s.handle_key(Key::Left), Some(Action::Jog(_))));
    }

    #[test]
    fn jog_keys_stream_velocities_scaled_and_follow_the_arm() {
        let mut s = ready(false);
        s.handle_key(Key::Char('v'));
        assert!(s.jog);
        s.handle_key(Key::Char('+'));
        let twist = |linear| {
            Some(Action::Jog(Velocity::Twist {
                linear,
                angular: [0.0; 3],
                frame: TwistFrame::Base,
            }))
        };
        assert_eq!(s.handle_key(Key::PageUp), twist([0.0, 0.0, 0.01]));
        assert_eq!(s.handle_key(Key::Left), twist([-0.01, 0.0, 0.0]));
        assert!(s.own_motion);
        // The desired pose is not edited: it follows the arm.
        s.apply(Event::Pose(pose(0.49, 0.2, 0.1)));
        assert_eq!(s.desired, Some(pose(0.49, 0.2, 0.1)));
        s.handle_key(Key::Char('j'));
        s.handle_key(Key::Char('3'));
        let mut rates = vec![0.0; 8];
        rates[2] = -0.04;
        assert_eq!(
            s.handle_key(Key::Left),
            Some(Action::Jog(Velocity::Joints(rates)))
        );
        s.handle_key(Key::Char('v'));
        assert_eq!(s.handle_key(Key::Left), None);
    }

    #[test]
    fn arrow_and_page_keys_move_the_desired_position() {
        let mut s = ready(false);
        let expectations = [
            (Key::Left, [0.499, 0.2, 0.1]),
            (Key::Right, [0.5, 0.2, 0.1]),
            (Key::Down, [0.5, 0.199, 0.1]),
            (Key::Up, [0.5, 0.2, 0.1]),
            (Key::PageDown, [0.5, 0.2, 0.099]),
            (Key::PageUp, [0.5, 0.2, 0.1]),
        ];
        for (key, xyz) in expectations {
            assert_eq!(s.handle_key(key), None, "{key:?} sends nothing until Enter");
            assert!(
                close(s.desired.unwrap().xyz, xyz),
                "{key:?}: {:?}",
                s.desired
            );
        }
        // The current pose is untouched.
        assert_eq!(s.current, Some(pose(0.5, 0.2, 0.1)));
    }

    #[test]
    fn scale_doubles_and_halves_within_limits() {
        let mut s = ready(false);
        s.handle_key(Key::Char('+'));
        s.handle_key(Key::Char('+'));
        assert_eq!(s.scale, 4.0);
        s.handle_key(Key::Right);
        assert!(close(s.desired.unwrap().xyz, [0.504, 0.2, 0.1]));
        s.handle_key(Key::Char('-'));
        assert_eq!(s.scale, 2.0);
        for _ in 0..20 {
            s.handle_key(Key::Char('-'));
        }
        assert_eq!(s.scale, SCALE_RANGE.0);
        for _ in 0..40 {
            s.handle_key(Key::Char('+'));
        }
        assert_eq!(s.scale, SCALE_RANGE.1);
    }

    #[test]
    fn c_resets_the_desired_pose_and_joints_space_stops_o_starts_the_drives() {
        let mut s = ready(false);
        s.handle_key(Key::Up);
        s.apply(Event::Pose(pose(0.4, 0.0, 0.3)));
        s.handle_key(Key::Char('c'));
        assert_eq!(s.desired, Some(pose(0.4, 0.0, 0.3)));
        s.desired_joints[0] = 1.0;
        s.handle_key(Key::Char('c'));
        assert_eq!(s.desired_joints, [0.0; 8]);
        assert_eq!(s.handle_key(Key::Char(' ')), Some(Action::Stop));
        assert_eq!(s.handle_key(Key::Char('o')), Some(Action::DrivesOn));
    }

    #[test]
    fn enter_sends_the_desired_position_with_the_current_orientation() {
        let mut s = ready(false);
        let tilted = Pose::from_xyz_rpy([0.5, 0.2, 0.1], [0.1, 0.2, 0.3]);
        s.apply(Event::Pose(tilted));
        s.handle_key(Key::PageUp);
        let Some(Action::MoveCartesian { xyz, rpy }) = s.handle_key(Key::Enter) else {
            panic!()
        };
        assert!(close(xyz, [0.5, 0.2, 0.101]));
        assert!(close(rpy.map(|v| (v * 1e9).round()), [0.1e9, 0.2e9, 0.3e9]));
        assert_eq!(s.desired.unwrap().quaternion, tilted.quaternion);
    }

    #[test]
    fn live_mode_sends_on_every_key() {
        let mut s = ready(true);
        assert!(matches!(
            s.handle_key(Key::Left),
            Some(Action::MoveCartesian { .. })
        ));
        s.handle_key(Key::Char('j'));
        assert!(matches!(
            s.handle_key(Key::Right),
            Some(Action::MoveJoints(_))
        ));
        // Selecting a joint is not a change.
        assert_eq!(s.handle_key(Key::Char('2')), None);
    }

    #[test]
    fn joint_variant_selects_and_moves_one_joint() {
        let mut s = ready(false);
        s.handle_key(Key::Char('j'));
        assert_eq!(s.variant, Variant::Joint);
        s.handle_key(Key::Char('8'));
        assert_eq!(s.selected, 7);
        s.handle_key(Key::Char('9'));
        assert_eq!(s.selected, 7);
        s.handle_key(Key::Right);
        s.handle_key(Key::Char('+'));
        s.handle_key(Key::Right);
        assert!((s.desired_joints[7] - 0.03).abs() < 1e-12);
        s.handle_key(Key::Up);
        assert_eq!(s.selected, 6);
        s.handle_key(Key::Left);
        assert!((s.desired_joints[6] + 0.02).abs() < 1e-12);
        s.handle_key(Key::Down);
        s.handle_key(Key::Down);
        assert_eq!(s.selected, 7);
        // PageUp means nothing in joint keys.
        assert_eq!(s.handle_key(Key::PageUp), None);
        let Some(Action::MoveJoints(q)) = s.handle_key(Key::Enter) else {
            panic!()
        };
        assert_eq!(q.len(), 8);
        s.handle_key(Key::Char('j'));
        assert_eq!(s.variant, Variant::Cartesian);
    }

    #[test]
    fn m_selects_the_mode_the_keys_need_then_cycles() {
        let mut s = ready(false);
        // Cartesian keys: m goes to Cartesian mode at once, not through off or joint.
        assert_eq!(
            s.handle_key(Key::Char('m')),
            Some(Action::SetMode(Mode::Cartesian))
        );
        s.apply(Event::Mode(Mode::Cartesian));
        // There: on along the cycle.
        assert_eq!(
            s.handle_key(Key::Char('m')),
            Some(Action::SetMode(Mode::Off))
        );
        // Pressed again before the answer: from the requested mode, back to the keys' one.
        assert_eq!(s.mode_pending, Some(Mode::Off));
        assert_eq!(
            s.handle_key(Key::Char('m')),
            Some(Action::SetMode(Mode::Cartesian))
        );
        s.apply(Event::ModeFailed);
        assert_eq!(s.mode_pending, None);
        assert_eq!(s.mode, Some(Mode::Cartesian));
        // Joint keys in Cartesian mode: m goes to joint mode directly.
        s.handle_key(Key::Char('j'));
        assert_eq!(
            s.handle_key(Key::Char('m')),
            Some(Action::SetMode(Mode::Joint))
        );
    }

    #[test]
    fn a_refusal_for_the_mode_says_press_m() {
        let mut s = ready(false);
        s.apply(Event::Refused(crate::fake::parsed_text(
            "ER20 Cmd TW needs mode 2",
        )));
        assert_eq!(s.status, "needs mode cartesian: press m");
    }

    fn status(mode: Mode, motion: Motion) -> Status {
        Status {
            mode,
            drives: crate::DriveStatus::Running,
            fault: 0,
            joints: 6,
            motion,
            refused: 0,
            uptime: 1.0,
            name: "ranger-mk1".into(),
            cause: None,
            session: None,
        }
    }

    /// A six-joint arm in Cartesian mode, with the status request.
    fn six(mode: Mode) -> TeleopState {
        let mut s = TeleopState::new("127.0.0.1:7031", 6, false);
        s.apply(Event::Controller(status(mode, Motion::Holding)));
        s.apply(Event::Pose(pose(0.0, 0.2, 0.8)));
        s.apply(Event::Joints(vec![1.57, 0.0, 1.57, 0.0, 1.57, 0.0]));
        s
    }

    fn measure(s: &mut TeleopState, xyz: [f64; 3], q: [f64; 6], motion: Option<Motion>) {
        if let Some(motion) = motion {
            let mode = s.mode.unwrap_or(Mode::Off);
            s.apply(Event::Controller(status(mode, motion)));
        }
        s.apply(Event::Pose(pose(xyz[0], xyz[1], xyz[2])));
        s.apply(Event::Joints(q.to_vec()));
    }

    #[test]
    fn after_a_cartesian_move_a_joint_key_moves_that_joint_only() {
        let mut s = six(Mode::Cartesian);
        s.handle_key(Key::Right);
        assert!(matches!(
            s.handle_key(Key::Enter),
            Some(Action::MoveCartesian { .. })
        ));
        s.apply(Event::Started("sent GT + BG".into()));
        // The move runs: the desired pose stays the goal, the joints follow.
        let moving = [1.56, 0.01, 1.58, 0.0, 1.56, 0.02];
        measure(
            &mut s,
            [0.0005, 0.2, 0.8],
            moving,
            Some(Motion::CartesianMove),
        );
        assert!(close(s.desired.unwrap().xyz, [0.001, 0.2, 0.8]));
        assert_eq!(s.desired_joints, moving);
        let end = [1.55, 0.02, 1.59, 0.0, 1.55, 0.03];
        measure(&mut s, [0.001, 0.2, 0.8], end, Some(Motion::Holding));
        assert!(!s.own_motion);
        assert_eq!(s.pose_edit, Edit::Following);
        // Joint mode (the mode switch), joint keys, j2 one step: only j2 differs.
        s.apply(Event::Mode(Mode::Joint));
        s.handle_key(Key::Char('j'));
        s.handle_key(Key::Char('2'));
        s.handle_key(Key::Right);
        let Some(Action::MoveJoints(q)) = s.handle_key(Key::Enter) else {
            panic!()
        };
        let mut expected = end.to_vec();
        expected[1] += BASE_JOINT_STEP;
        assert_eq!(q, expected);
    }

    #[test]
    fn after_another_clients_move_one_key_is_one_step_from_where_the_arm_is() {
        let mut s = six(Mode::Cartesian);
        // An edit not sent yet ...
        s.handle_key(Key::Up);
        s.handle_key(Key::Up);
        assert_eq!(s.pose_edit, Edit::Unsent);
        // ... then another client moves the arm far away.
        let q = [1.0, 0.3, 1.2, 0.0, 1.2, 0.0];
        measure(&mut s, [0.1, 0.3, 0.7], q, Some(Motion::CartesianMove));
        assert_eq!(s.pose_edit, Edit::Following);
        assert!(s.status.contains("desired <- current"), "{}", s.status);
        measure(&mut s, [0.2, 0.3, 0.7], q, Some(Motion::Holding));
        s.handle_key(Key::Right);
        let Some(Action::MoveCartesian { xyz, .. }) = s.handle_key(Key::Enter) else {
            panic!()
        };
        assert!(close(xyz, [0.201, 0.3, 0.7]), "{xyz:?}");
    }

    #[test]
    fn without_the_status_request_motion_is_seen_in_the_readings() {
        let mut s = ready(false);
        s.handle_key(Key::Up);
        // Another client moves the arm: the edit is void.
        s.apply(Event::Pose(pose(0.4, 0.2, 0.1)));
        assert_eq!(s.desired, Some(pose(0.4, 0.2, 0.1)));
        // Own motion: the goal stays while the arm moves, until it has been still a while.
        s.handle_key(Key::Right);
        s.handle_key(Key::Enter);
        s.apply(Event::Started("sent GT + BG".into()));
        s.apply(Event::Pose(pose(0.4005, 0.2, 0.1)));
        s.apply(Event::Pose(pose(0.4009, 0.2, 0.1)));
        assert!(close(s.desired.unwrap().xyz, [0.401, 0.2, 0.1]));
        for _ in 0..STILL_POLLS {
            assert!(s.own_motion);
            s.apply(Event::Pose(pose(0.4009, 0.2, 0.1)));
        }
        assert!(!s.own_motion);
        assert_eq!(s.desired, Some(pose(0.4009, 0.2, 0.1)));
    }

    #[test]
    fn edits_made_while_the_own_motion_runs_are_kept() {
        let mut s = six(Mode::Cartesian);
        s.handle_key(Key::Right);
        s.handle_key(Key::Enter);
        s.apply(Event::Started("sent GT + BG".into()));
        let q = [1.57, 0.0, 1.57, 0.0, 1.57, 0.0];
        measure(&mut s, [0.0005, 0.2, 0.8], q, Some(Motion::CartesianMove));
        s.handle_key(Key::PageUp);
        measure(&mut s, [0.001, 0.2, 0.8], q, Some(Motion::Holding));
        assert_eq!(s.pose_edit, Edit::Unsent);
        assert!(close(s.desired.unwrap().xyz, [0.001, 0.2, 0.801]));
    }

    #[test]
    fn a_mode_switch_drops_edits_and_a_refusal_marks_the_goal() {
        let mut s = six(Mode::Cartesian);
        s.handle_key(Key::Up);
        s.apply(Event::Controller(status(Mode::Joint, Motion::Holding)));
        assert_eq!(s.pose_edit, Edit::Following);
        assert_eq!(s.desired, s.current);
        s.handle_key(Key::Char('j'));
        s.handle_key(Key::Right);
        s.handle_key(Key::Enter);
        let text = crate::fake::parsed_text("ER26 Cmd jG j1 > 4.713");
        s.apply(Event::Refused(text));
        assert_eq!(s.refused, Some(text));
        assert_eq!(s.joints_edit, Edit::Unsent);
        assert_eq!(s.recent_text(), Some(&text));
        s.handle_key(Key::Char('c'));
        assert_eq!(s.refused, None);
        assert_eq!(s.desired_joints, s.joints);
    }

    #[test]
    fn q_and_esc_quit() {
        for key in [Key::Char('q'), Key::Esc] {
            let mut s = ready(false);
            assert_eq!(s.handle_key(key), None);
            assert!(s.quit);
        }
    }

    #[test]
    fn texts_and_status_are_kept() {
        let mut s = ready(false);
        let text = crate::fake::parsed_text("WN12 Joint limit.");
        s.apply(Event::Text(text));
        assert_eq!(s.last_text, Some(text));
        assert_eq!(s.recent_text(), Some(&text));
        s.at(s.now + TEXT_SHOWN);
        assert_eq!(s.recent_text(), None);
        s.apply(Event::Status("sent GT + BG".into()));
        assert_eq!(s.status, "sent GT + BG");
    }
}
