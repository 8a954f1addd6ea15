//! The control mode as `CM` selects it and `MC` echoes it.

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
    use super::Mode;

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
