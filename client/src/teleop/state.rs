//! The keyboard client's state and its key handling, free of any terminal or socket.

use crate::{Mode, Pose, Text, next_mode};

/// The base Cartesian step per key press (m), multiplied by the scale.
pub const BASE_STEP: f64 = 0.001;

/// The base joint step per key press (rad, or m for prismatic joints), multiplied by the scale.
pub const BASE_JOINT_STEP: f64 = 0.01;

/// The smallest and largest scale.
pub const SCALE_RANGE: (f64, f64) = (1.0 / 64.0, 1024.0);

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
    /// The latest status line.
    pub status: String,
    /// Set by q / Esc.
    pub quit: bool,
}

impl TeleopState {
    /// The state before any reply.
    pub fn new(addr: impl Into<String>, joint_count: usize, live: bool) -> Self {
        Self {
            addr: addr.into(),
            variant: Variant::Cartesian,
            live,
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
            status: String::from("waiting for the controller"),
            quit: false,
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
                self.current = Some(pose);
                if self.desired.is_none() {
                    self.desired = Some(pose);
                }
            }
            Event::Joints(q) => {
                if self.desired_joints.len() != q.len() {
                    self.desired_joints.clone_from(&q);
                }
                self.joints = q;
            }
            Event::Temperatures(t) => self.temperatures = t,
            Event::Text(text) => self.last_text = Some(text),
            Event::Mode(mode) => {
                self.mode = Some(mode);
                self.mode_pending = None;
                self.status = format!("mode {}", mode.name());
            }
            Event::ModeFailed => self.mode_pending = None,
            Event::Status(status) => self.status = status,
        }
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
                self.desired = self.current;
                self.desired_joints.clone_from(&self.joints);
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
            Key::Char('m') => {
                let next = next_mode(self.mode_pending.or(self.mode).unwrap_or(Mode::Off));
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
        let step = self.step();
        let Some(desired) = self.desired.as_mut() else {
            self.status = String::from("no pose from the controller yet");
            return None;
        };
        if let Some(v) = desired.xyz.get_mut(axis) {
            *v += sign * step;
        }
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
        let step = self.joint_step();
        let Some(q) = self.desired_joints.get_mut(self.selected) else {
            self.status = String::from("no joints from the controller yet");
            return None;
        };
        *q += sign * step;
        self.edited()
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
    fn first_replies_initialise_the_desired_values() {
        let mut s = TeleopState::new("a", 6, false);
        assert_eq!(s.handle_key(Key::Right), None);
        assert_eq!(s.status, "no pose from the controller yet");
        s.apply(Event::Pose(pose(0.5, 0.2, 0.1)));
        assert_eq!(s.desired, Some(pose(0.5, 0.2, 0.1)));
        s.apply(Event::Pose(pose(0.6, 0.2, 0.1)));
        assert_eq!(s.desired, Some(pose(0.5, 0.2, 0.1)));
        s.apply(Event::Joints(vec![1.0; 6]));
        s.apply(Event::Joints(vec![2.0; 6]));
        assert_eq!(s.desired_joints, [1.0; 6]);
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
    fn space_resets_the_desired_pose_and_joints() {
        let mut s = ready(false);
        s.handle_key(Key::Up);
        s.apply(Event::Pose(pose(0.4, 0.0, 0.3)));
        s.handle_key(Key::Char(' '));
        assert_eq!(s.desired, Some(pose(0.4, 0.0, 0.3)));
        s.desired_joints[0] = 1.0;
        s.handle_key(Key::Char(' '));
        assert_eq!(s.desired_joints, [0.0; 8]);
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
    fn m_cycles_the_mode_from_the_reported_one() {
        let mut s = ready(false);
        assert_eq!(
            s.handle_key(Key::Char('m')),
            Some(Action::SetMode(Mode::Joint))
        );
        s.apply(Event::Mode(Mode::Joint));
        assert_eq!(
            s.handle_key(Key::Char('m')),
            Some(Action::SetMode(Mode::Cartesian))
        );
        s.apply(Event::Mode(Mode::Cartesian));
        assert_eq!(
            s.handle_key(Key::Char('m')),
            Some(Action::SetMode(Mode::Off))
        );
        // Pressed again before the answer: cycles on from the requested mode.
        assert_eq!(s.mode_pending, Some(Mode::Off));
        assert_eq!(
            s.handle_key(Key::Char('m')),
            Some(Action::SetMode(Mode::Joint))
        );
        s.apply(Event::ModeFailed);
        assert_eq!(s.mode_pending, None);
        assert_eq!(s.mode, Some(Mode::Cartesian));
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
        s.apply(Event::Status("sent GT + BG".into()));
        assert_eq!(s.status, "sent GT + BG");
    }
}
