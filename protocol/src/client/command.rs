//! The client's request commands (spec §2.5).

/// A request command. The doc of each variant starts with its two characters.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Command {
    /// `BG`: begin the Cartesian motion to the stored goal.
    Begin,
    /// `CM`: change the control mode to f0 (0 off, 1 joint, 2 Cartesian).
    ChangeMode,
    /// `GL`: store the Cartesian goal: position f0..f2, quaternion f3..f6 (x, y, z, w).
    GoalQuaternion,
    /// `GT`: store the Cartesian goal: position f0..f2, roll/pitch/yaw f3..f5, duration f6.
    GoalRpy,
    /// `KG`: move the joints (joint mode) to the inverse kinematics of the pose f0..f2,
    /// roll/pitch/yaw f3..f5, in at least f6 s, on the configuration branch `index` (bits:
    /// [`branch`](super::branch)); [`NEAREST_BRANCH`](super::branch::NEAREST_BRANCH): the
    /// solution nearest the present joints.
    IkGoal,
    /// `KR`: choose the redundancy parameters (f0 θ3, f1 θ5; index bits:
    /// [`redundancy`](super::redundancy)) of this client's next `KG` and its `KS` reads, on an
    /// arm of seven or eight joints with a closed form.
    IkRedundancy,
    /// `KS`: read the `index`-th closed-form IK solution of the pose f0..f2, roll/pitch/yaw
    /// f3..f5 (0 first; index bit 7, bank 2: its joints 7.. in f0..).
    IkSolution,
    /// `jB`: begin the joint motion to the stored joint goal.
    JointBegin,
    /// `jC`: clear the joint via points.
    JointClear,
    /// `jE`: execute the joint via-point sequence.
    JointExecute,
    /// `jG`: store the joint goal f0..f5.
    JointGoal,
    /// `jP`: read the measured joints.
    JointPosition,
    /// `jR`: stop a joint motion, as `ST`: the arm holds its commanded position (the seed reset
    /// the joint generator to the measured joints).
    JointReset,
    /// `jV`: store joint via point `index`: joints f0..f5, duration f6.
    JointVia,
    /// `jT`: set the blend tolerance of joint via point `index` to f0 (rad; negative: the
    /// robot file's default).
    JointViaTolerance,
    /// `jW`: stream joint rates f0..f5 (bank 2, index bit 7: joints 7..); valid for three
    /// control periods (joint mode).
    JointVelocity,
    /// `ON`: start the arm.
    On,
    /// `OF`: stop the arm.
    Off,
    /// `PS`: read the measured tool pose.
    Pose,
    /// `RC`: recalibrate: the current joint angles are f0..f5.
    Recalibrate,
    /// `SQ`: report the status (index 0), the robot's name (index 1) or the present IK
    /// configuration branch (index 5).
    Status,
    /// `ST`: stop all motion.
    Stop,
    /// `TM`: read the drive temperatures.
    Temperature,
    /// `TW`: stream a tool twist: linear f0..f2 (m/s), angular f3..f5 (rad/s), base frame or
    /// (index bit 0) tool frame; valid for three control periods (Cartesian mode).
    Twist,
    /// `VC`: clear the Cartesian via points.
    ViaClear,
    /// `VE`: execute the Cartesian via-point sequence.
    ViaExecute,
    /// `VP`: store Cartesian via point `index`: position f0..f2, roll/pitch/yaw f3..f5,
    /// duration f6.
    ViaPoint,
    /// `VT`: set the blend tolerance of Cartesian via point `index` to f0 (m + rad; negative:
    /// the robot file's default).
    ViaTolerance,
    /// `WD`: the client watchdog: while the arm moves and the controlling client is silent for
    /// longer than f0 ms, the arm is stopped (0: off).
    Watchdog,
}

impl Command {
    /// Every command, in the order of the spec's table.
    pub const ALL: [Self; 29] = [
        Self::Begin,
        Self::ChangeMode,
        Self::GoalQuaternion,
        Self::GoalRpy,
        Self::IkGoal,
        Self::IkRedundancy,
        Self::IkSolution,
        Self::JointBegin,
        Self::JointClear,
        Self::JointExecute,
        Self::JointGoal,
        Self::JointPosition,
        Self::JointReset,
        Self::JointVia,
        Self::JointViaTolerance,
        Self::JointVelocity,
        Self::On,
        Self::Off,
        Self::Pose,
        Self::Recalibrate,
        Self::Status,
        Self::Stop,
        Self::Temperature,
        Self::Twist,
        Self::ViaClear,
        Self::ViaExecute,
        Self::ViaPoint,
        Self::ViaTolerance,
        Self::Watchdog,
    ];

    /// The request's two characters.
    pub const fn chars(self) -> [u8; 2] {
        *match self {
            Self::Begin => b"BG",
            Self::ChangeMode => b"CM",
            Self::GoalQuaternion => b"GL",
            Self::GoalRpy => b"GT",
            Self::IkGoal => b"KG",
            Self::IkRedundancy => b"KR",
            Self::IkSolution => b"KS",
            Self::JointBegin => b"jB",
            Self::JointClear => b"jC",
            Self::JointExecute => b"jE",
            Self::JointGoal => b"jG",
            Self::JointPosition => b"jP",
            Self::JointReset => b"jR",
            Self::JointVia => b"jV",
            Self::JointViaTolerance => b"jT",
            Self::JointVelocity => b"jW",
            Self::On => b"ON",
            Self::Off => b"OF",
            Self::Pose => b"PS",
            Self::Recalibrate => b"RC",
            Self::Status => b"SQ",
            Self::Stop => b"ST",
            Self::Temperature => b"TM",
            Self::Twist => b"TW",
            Self::ViaClear => b"VC",
            Self::ViaExecute => b"VE",
            Self::ViaPoint => b"VP",
            Self::ViaTolerance => b"VT",
            Self::Watchdog => b"WD",
        }
    }

    /// The reply's two characters: the request's, reversed (`BG` → `GB`, and `VC` → `CV`,
    /// where the seed answered `PV`).
    pub const fn reply_chars(self) -> [u8; 2] {
        let [a, b] = self.chars();
        [b, a]
    }

    /// The command with these request characters (case-sensitive).
    pub fn from_chars(chars: [u8; 2]) -> Option<Self> {
        Self::ALL.into_iter().find(|c| c.chars() == chars)
    }

    /// The command whose reply has these characters.
    pub fn from_reply_chars(chars: [u8; 2]) -> Option<Self> {
        Self::ALL.into_iter().find(|c| c.reply_chars() == chars)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chars_are_unique_and_round_trip() {
        for (i, c) in Command::ALL.into_iter().enumerate() {
            assert_eq!(Command::from_chars(c.chars()), Some(c));
            assert_eq!(Command::from_reply_chars(c.reply_chars()), Some(c));
            assert!(Command::ALL[..i].iter().all(|d| d.chars() != c.chars()));
        }
    }

    #[test]
    fn lookup_is_case_sensitive_and_directional() {
        assert_eq!(Command::from_chars(*b"jV"), Some(Command::JointVia));
        assert_eq!(Command::from_chars(*b"JV"), None);
        assert_eq!(Command::from_chars(*b"GB"), None);
        assert_eq!(Command::from_reply_chars(*b"GB"), Some(Command::Begin));
        assert_eq!(Command::from_reply_chars(*b"CV"), Some(Command::ViaClear));
        assert_eq!(Command::from_chars(*b"SQ"), Some(Command::Status));
        assert_eq!(Command::from_reply_chars(*b"QS"), Some(Command::Status));
    }
}
