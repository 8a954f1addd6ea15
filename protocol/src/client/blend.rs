//! The blend-tolerance requests (docs/protocol.md, "Blend tolerances"): `VT` for a Cartesian
//! via-point slot, `jT` for a joint one. The seed's `VP`/`jV` have no free field, so a slot's
//! tolerance travels on its own: f0 = the tolerance, the index byte = the slot, like `VP`.
//!
//! ```
//! use armgate_protocol::client::{BlendTolerance, Command, ViaKind};
//!
//! let tolerance = BlendTolerance { kind: ViaKind::Joint, slot: 3, tolerance: Some(0.05) };
//! let request = tolerance.to_request();
//! assert_eq!((request.command, request.index), (Command::JointViaTolerance, 3));
//! assert_eq!(BlendTolerance::parse(&request), Ok(tolerance));
//!
//! // A negative value gives the slot back the robot file's default.
//! let default = BlendTolerance { kind: ViaKind::Cartesian, slot: 0, tolerance: None };
//! assert_eq!(default.to_request().values[0], -1.0);
//! ```

use super::{Command, DecodeError, Request, VALUES};

/// Which via-point slots a tolerance is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ViaKind {
    /// The Cartesian slots of `VP` (`VT`; m + rad, the via-point distance).
    Cartesian,
    /// The joint slots of `jV` (`jT`; rad, Euclidean over the joints).
    Joint,
}

/// `VT` or `jT`: the blend tolerance of one via-point slot. The reply (`TV`, `Tj`) carries
/// the tolerance then in effect for the slot in f0 and the slot in the index.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BlendTolerance {
    /// Cartesian or joint slots.
    pub kind: ViaKind,
    /// The slot (0..20; the controller refuses others, as for `VP`).
    pub slot: u8,
    /// The slot's own tolerance (≥ 0; 0 stops there), or `None` for the robot file's default
    /// (sent as −1: any finite negative value). Kept as received otherwise: NaN and the
    /// infinities, −∞ too, are the controller's to refuse (`ER23`).
    pub tolerance: Option<f32>,
}

impl BlendTolerance {
    /// The tolerance of a `VT` or `jT` request.
    pub fn parse(request: &Request) -> Result<Self, DecodeError> {
        let kind = match request.command {
            Command::ViaTolerance => ViaKind::Cartesian,
            Command::JointViaTolerance => ViaKind::Joint,
            _ => return Err(DecodeError::WrongCommand),
        };
        let [value, ..] = request.values;
        Ok(Self {
            kind,
            slot: request.index,
            tolerance: if value < 0.0 && value.is_finite() {
                None
            } else {
                Some(value)
            },
        })
    }

    /// The request.
    pub fn to_request(&self) -> Request {
        let mut values = [0.0; VALUES];
        if let Some(first) = values.first_mut() {
            *first = self.tolerance.unwrap_or(-1.0);
        }
        Request {
            command: match self.kind {
                ViaKind::Cartesian => Command::ViaTolerance,
                ViaKind::Joint => Command::JointViaTolerance,
            },
            values,
            index: self.slot,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::client::vectors::{ZERO, datagram, request};
    use crate::client::{MESSAGE_LEN, Message, Reply};

    /// `VT` slot 2 at 0.01 (m + rad), byte for byte.
    const VT_SLOT_2: [u8; MESSAGE_LEN] = datagram(
        *b"VT",
        [[0x0a, 0xd7, 0x23, 0x3c], ZERO, ZERO, ZERO, ZERO, ZERO, ZERO], // 0.01
        0x02,
    );

    /// `jT` slot 19 back to the default (−1).
    const JT_DEFAULT_19: [u8; MESSAGE_LEN] = datagram(
        *b"jT",
        [[0x00, 0x00, 0x80, 0xbf], ZERO, ZERO, ZERO, ZERO, ZERO, ZERO], // -1.0
        0x13,
    );

    /// The reply `Tj` to a `jT` that set slot 4 to 0.5 rad.
    const TJ_SLOT_4: [u8; MESSAGE_LEN] = datagram(
        *b"Tj",
        [[0x00, 0x00, 0x00, 0x3f], ZERO, ZERO, ZERO, ZERO, ZERO, ZERO], // 0.5
        0x04,
    );

    #[test]
    fn vt_parses_and_emits_its_literal_bytes() {
        let parsed = BlendTolerance::parse(&request(&VT_SLOT_2)).unwrap();
        let expected = BlendTolerance {
            kind: ViaKind::Cartesian,
            slot: 2,
            tolerance: Some(0.01),
        };
        assert_eq!(parsed, expected);
        assert_eq!(expected.to_request().to_bytes(), VT_SLOT_2);
    }

    /// −∞ is not "the default" but a number the controller refuses, as it does NaN and +∞.
    #[test]
    fn an_infinite_tolerance_is_kept_for_the_controller_to_refuse() {
        for value in [f32::NEG_INFINITY, f32::INFINITY] {
            let mut request = request(&VT_SLOT_2);
            request.values[0] = value;
            let parsed = BlendTolerance::parse(&request).unwrap();
            assert_eq!(parsed.tolerance, Some(value));
        }
    }

    #[test]
    fn jt_with_a_negative_value_means_the_default() {
        let parsed = BlendTolerance::parse(&request(&JT_DEFAULT_19)).unwrap();
        let expected = BlendTolerance {
            kind: ViaKind::Joint,
            slot: 19,
            tolerance: None,
        };
        assert_eq!(parsed, expected);
        assert_eq!(expected.to_request().to_bytes(), JT_DEFAULT_19);
        let mut minus_two = request(&JT_DEFAULT_19);
        minus_two.values[0] = -2.0;
        assert_eq!(BlendTolerance::parse(&minus_two), Ok(expected));
    }

    #[test]
    fn nan_and_zero_are_kept_for_the_controller() {
        let mut nan = request(&VT_SLOT_2);
        nan.values[0] = f32::NAN;
        let parsed = BlendTolerance::parse(&nan).unwrap();
        assert!(parsed.tolerance.is_some_and(f32::is_nan));
        nan.values[0] = 0.0;
        assert_eq!(BlendTolerance::parse(&nan).unwrap().tolerance, Some(0.0));
    }

    #[test]
    fn other_commands_are_not_tolerances() {
        let mut vp = request(&VT_SLOT_2);
        vp.command = Command::ViaPoint;
        assert_eq!(BlendTolerance::parse(&vp), Err(DecodeError::WrongCommand));
    }

    #[test]
    fn the_reply_reverses_the_characters() {
        let reply = Message::new_checked(&TJ_SLOT_4[..])
            .and_then(|m| Reply::parse(&m))
            .unwrap();
        assert_eq!(reply.command, Command::JointViaTolerance);
        assert_eq!((reply.values[0], reply.index), (0.5, 4));
        let mut values = [0.0; VALUES];
        values[0] = 0.5;
        let emitted = Reply {
            command: Command::JointViaTolerance,
            values,
            index: 4,
        };
        assert_eq!(emitted.to_bytes(), TJ_SLOT_4);
        assert_eq!(
            Command::ViaTolerance.reply_chars(),
            *b"TV",
            "VT is answered TV"
        );
    }
}
