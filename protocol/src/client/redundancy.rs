//! The redundancy parameters of an arm of seven or eight joints on the wire (`KR`, and the
//! `KG`/`KS` index bit that uses them).
//!
//! `KR` carries θ3 in f0 and θ5 (eight joints) in f1, each used only if its index bit
//! ([`THETA3`], [`THETA5`]) is set; a parameter not chosen keeps its present value. The choice
//! belongs to the client that sent it and is used by that client's `KG` or `KS` with
//! [`CHOSEN`] in the index, so a choice that was lost or cleared is a refusal, never a move
//! with other values. The rules of when a choice lasts are the controller's (docs/protocol.md).

use super::VALUES;

/// `KR` index bit: f0 is θ3 (rad).
pub const THETA3: u8 = 1;
/// `KR` index bit: f1 is θ5 (rad; eight joints only).
pub const THETA5: u8 = 2;
/// `KG` and `KS` index bit: solve with this client's `KR` choice.
pub const CHOSEN: u8 = 0x40;

/// A `KR` choice: the values of the redundancy parameters, `None` for the present one.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Redundancy {
    /// θ3 (rad).
    pub theta3: Option<f32>,
    /// θ5 (rad).
    pub theta5: Option<f32>,
}

impl Redundancy {
    /// The choice of a `KR` request's values and index; `None` if the index has a bit that is
    /// neither [`THETA3`] nor [`THETA5`]. The values are as sent (NaN included).
    pub fn parse(values: &[f32; VALUES], index: u8) -> Option<Self> {
        if index & !(THETA3 | THETA5) != 0 {
            return None;
        }
        let [f0, f1, ..] = *values;
        Some(Self {
            theta3: (index & THETA3 != 0).then_some(f0),
            theta5: (index & THETA5 != 0).then_some(f1),
        })
    }

    /// The `KR` request's values and index (and `RK`'s: the reply repeats them), zero where
    /// a parameter is not chosen.
    pub fn emit(&self) -> ([f32; VALUES], u8) {
        let mut values = [0.0; VALUES];
        let mut index = 0;
        for (slot, (value, bit)) in values
            .iter_mut()
            .zip([(self.theta3, THETA3), (self.theta5, THETA5)])
        {
            if let Some(v) = value {
                *slot = v;
                index |= bit;
            }
        }
        (values, index)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_choice_round_trips_and_other_bits_are_refused() {
        let both = Redundancy {
            theta3: Some(0.5),
            theta5: Some(-1.25),
        };
        let (values, index) = both.emit();
        assert_eq!((values, index), ([0.5, -1.25, 0.0, 0.0, 0.0, 0.0, 0.0], 3));
        assert_eq!(Redundancy::parse(&values, index), Some(both));
        // Only θ3: f1 is not read.
        let values = [0.5, 9.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        assert_eq!(
            Redundancy::parse(&values, THETA3),
            Some(Redundancy {
                theta3: Some(0.5),
                theta5: None
            })
        );
        assert_eq!(Redundancy::parse(&values, 0), Some(Redundancy::default()));
        assert_eq!(Redundancy::default().emit(), ([0.0; VALUES], 0));
        assert_eq!(Redundancy::parse(&values, 4), None);
        assert_eq!(Redundancy::parse(&values, CHOSEN | THETA3), None);
    }
}
