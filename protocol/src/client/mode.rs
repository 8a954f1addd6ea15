//! The control mode as `CM` selects it and `MC` echoes it, and the mode each motion request
//! needs (the controller refuses it in another with `ER20 Cmd XX needs mode N`).

use super::Command;

/// The controller's control mode (the seed's switch: off / joint / Cartesian).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Mode {
    /// 0: no command; the drives hold their last set-point.
    #[default]
    Off,
    /// 1: the joint generator, joint sequences and joint-rate streams drive the arm (jB, jE,
    /// jW).
    Joint,
    /// 2: the Cartesian generator, shapes, Cartesian sequences and twist streams drive the arm
    /// (BG, VE, TW).
    Cartesian,
}

impl Mode {
    /// Every mode, by value.
    pub const ALL: [Self; 3] = [Self::Off, Self::Joint, Self::Cartesian];

    /// The value in f0 of `CM` and `MC`.
    pub const fn value(self) -> u8 {
        match self {
            Self::Off => 0,
            Self::Joint => 1,
            Self::Cartesian => 2,
        }
    }

    /// The mode whose value is nearest to `value`, halves rounding up (the seed's
    /// `floor(f0 + 0.5)`); `None` for anything else, NaN included.
    pub fn from_value(value: f32) -> Option<Self> {
        let v = f64::from(value);
        Self::ALL.into_iter().find(|m| {
            let centre = f64::from(m.value());
            centre - 0.5 <= v && v < centre + 0.5
        })
    }

    /// The mode `command` needs, if it needs one: the motions and streams of each mode, and
    /// `RC` (mode off). The controller checks it; clients name it in their hints.
    pub const fn required_by(command: Command) -> Option<Self> {
        match command {
            Command::Begin | Command::ViaExecute | Command::Twist => Some(Self::Cartesian),
            Command::JointBegin
            | Command::JointExecute
            | Command::JointVelocity
            | Command::IkGoal => Some(Self::Joint),
            Command::Recalibrate => Some(Self::Off),
            _ => None,
        }
    }

    /// The mode's lower-case name, as status lines show it.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Off => "off",
            Self::Joint => "joint",
            Self::Cartesian => "cartesian",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{Command, Mode};

    #[test]
    fn motions_need_their_mode_and_setters_none() {
        assert_eq!(Mode::required_by(Command::Begin), Some(Mode::Cartesian));
        assert_eq!(Mode::required_by(Command::Twist), Some(Mode::Cartesian));
        assert_eq!(Mode::required_by(Command::JointExecute), Some(Mode::Joint));
        assert_eq!(Mode::required_by(Command::IkGoal), Some(Mode::Joint));
        assert_eq!(Mode::required_by(Command::Recalibrate), Some(Mode::Off));
        assert_eq!(Mode::required_by(Command::GoalRpy), None);
        assert_eq!(Mode::required_by(Command::JointGoal), None);
        assert_eq!(Mode::required_by(Command::Stop), None);
    }

    #[test]
    fn values_round_half_up_and_refuse_the_rest() {
        assert_eq!(Mode::from_value(1.9), Some(Mode::Cartesian));
        assert_eq!(Mode::from_value(1.5), Some(Mode::Cartesian));
        assert_eq!(Mode::from_value(1.4999999), Some(Mode::Joint));
        assert_eq!(Mode::from_value(-0.5), Some(Mode::Off));
        assert_eq!(Mode::from_value(-0.51), None);
        assert_eq!(Mode::from_value(2.5), None);
        assert_eq!(Mode::from_value(f32::NAN), None);
        assert_eq!(Mode::from_value(f32::INFINITY), None);
        for m in Mode::ALL {
            assert_eq!(Mode::from_value(f32::from(m.value())), Some(m));
        }
    }
}
