//! The velocity-streaming requests (docs/protocol.md, "Velocity streaming"): `TW`, a tool
//! twist, and `jW`, joint rates. Each holds for three control periods; a client streams them
//! faster than that, and when they stop the arm ramps to rest.
//!
//! ```
//! use armgate_protocol::client::{Command, JointRates, Twist, TwistFrame};
//!
//! let twist = Twist { linear: [0.01, 0.0, 0.0], angular: [0.0; 3], frame: TwistFrame::Tool };
//! let request = twist.to_request();
//! assert_eq!((request.command, request.index), (Command::Twist, 0x01));
//! assert_eq!(Twist::parse(&request), Ok(twist));
//!
//! let upper = JointRates { bank_2: true, rates: [0.1, -0.1, 0.0, 0.0, 0.0, 0.0] };
//! assert_eq!(upper.to_request().index, 0x80);
//! ```

use super::banks::{BANK_2, WRITE_JOINTS};
use super::{Command, Request, VALUES};

/// Index bit of `TW`: the twist is in the tool frame (else the base frame).
pub const TOOL_FRAME: u8 = 0x01;

/// The frame a twist's components are given in. Either way the linear part is the velocity of
/// the tool origin.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TwistFrame {
    /// The robot's base frame (index 0).
    Base,
    /// The tool frame as it is at each tick (index [`TOOL_FRAME`]).
    Tool,
}

/// Why a request is not a valid `TW` or `jW`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum VelocityError {
    /// The request is another command.
    WrongCommand,
    /// The index has bits set that the command does not define.
    BadIndex,
}

/// `TW`: a tool twist, f0..f2 linear (m/s), f3..f5 angular (rad/s), f6 unused (0).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Twist {
    /// vx, vy, vz of the tool origin (m/s).
    pub linear: [f32; 3],
    /// ωx, ωy, ωz (rad/s).
    pub angular: [f32; 3],
    /// The frame of both parts.
    pub frame: TwistFrame,
}

impl Twist {
    /// The twist of a `TW` request. The values are kept as received: finiteness and limits
    /// are the controller's to judge.
    pub fn parse(request: &Request) -> Result<Self, VelocityError> {
        if request.command != Command::Twist {
            return Err(VelocityError::WrongCommand);
        }
        let frame = match request.index {
            0 => TwistFrame::Base,
            TOOL_FRAME => TwistFrame::Tool,
            _ => return Err(VelocityError::BadIndex),
        };
        let [vx, vy, vz, wx, wy, wz, _] = request.values;
        Ok(Self {
            linear: [vx, vy, vz],
            angular: [wx, wy, wz],
            frame,
        })
    }

    /// The `TW` request.
    pub fn to_request(&self) -> Request {
        let [vx, vy, vz] = self.linear;
        let [wx, wy, wz] = self.angular;
        Request {
            command: Command::Twist,
            values: [vx, vy, vz, wx, wy, wz, 0.0],
            index: match self.frame {
                TwistFrame::Base => 0,
                TwistFrame::Tool => TOOL_FRAME,
            },
        }
    }
}

/// `jW`: joint rates (rad/s, or m/s for prismatic joints) of one bank, f0..f5, f6 unused (0).
///
/// As for `jG`: an arm of up to six joints sends bank 1 alone; a 7–8-joint arm sends bank 2
/// (index bit 7, joints 7.. in f0..) first, and the bank-1 request completes the vector
/// ([`banks`](super::banks)).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct JointRates {
    /// Bank 2 (joints 7..) rather than bank 1 (joints 1..6).
    pub bank_2: bool,
    /// The rates of this bank's joints, zero-padded.
    pub rates: [f32; WRITE_JOINTS],
}

impl JointRates {
    /// The rates of a `jW` request.
    pub fn parse(request: &Request) -> Result<Self, VelocityError> {
        if request.command != Command::JointVelocity {
            return Err(VelocityError::WrongCommand);
        }
        let bank_2 = match request.index {
            0 => false,
            BANK_2 => true,
            _ => return Err(VelocityError::BadIndex),
        };
        let [r0, r1, r2, r3, r4, r5, _] = request.values;
        Ok(Self {
            bank_2,
            rates: [r0, r1, r2, r3, r4, r5],
        })
    }

    /// The `jW` request.
    pub fn to_request(&self) -> Request {
        let mut values = [0.0; VALUES];
        for (v, r) in values.iter_mut().zip(self.rates) {
            *v = r;
        }
        Request {
            command: Command::JointVelocity,
            values,
            index: if self.bank_2 { BANK_2 } else { 0 },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::client::vectors::{ZERO, datagram, request};
    use crate::client::{MESSAGE_LEN, Message, Reply};

    /// `TW` with vx = 0.5 m/s, ωz = −1 rad/s, tool frame, byte for byte.
    const TW_TOOL: [u8; MESSAGE_LEN] = datagram(
        *b"TW",
        [
            [0x00, 0x00, 0x00, 0x3f], // 0.5
            ZERO,
            ZERO,
            ZERO,
            ZERO,
            [0x00, 0x00, 0x80, 0xbf], // -1.0
            ZERO,
        ],
        0x01,
    );

    /// `jW` bank 2 with joint 7 at 0.25 rad/s and joint 8 at −2 rad/s.
    const JW_BANK_2: [u8; MESSAGE_LEN] = datagram(
        *b"jW",
        [
            [0x00, 0x00, 0x80, 0x3e], // 0.25
            [0x00, 0x00, 0x00, 0xc0], // -2.0
            ZERO,
            ZERO,
            ZERO,
            ZERO,
            ZERO,
        ],
        0x80,
    );

    #[test]
    fn twist_parses_and_emits_its_literal_bytes() {
        let twist = Twist::parse(&request(&TW_TOOL)).unwrap();
        let expected = Twist {
            linear: [0.5, 0.0, 0.0],
            angular: [0.0, 0.0, -1.0],
            frame: TwistFrame::Tool,
        };
        assert_eq!(twist, expected);
        assert_eq!(expected.to_request().to_bytes(), TW_TOOL);
        let mut base = TW_TOOL;
        base[30] = 0;
        assert_eq!(
            Twist::parse(&request(&base)).unwrap().frame,
            TwistFrame::Base
        );
    }

    #[test]
    fn joint_rates_parse_and_emit_their_literal_bytes() {
        let rates = JointRates::parse(&request(&JW_BANK_2)).unwrap();
        let expected = JointRates {
            bank_2: true,
            rates: [0.25, -2.0, 0.0, 0.0, 0.0, 0.0],
        };
        assert_eq!(rates, expected);
        assert_eq!(expected.to_request().to_bytes(), JW_BANK_2);
    }

    #[test]
    fn replies_reverse_the_characters() {
        let reply = |c| Reply::null(c).to_bytes();
        assert_eq!(reply(Command::Twist)[..2], *b"WT");
        assert_eq!(reply(Command::JointVelocity)[..2], *b"Wj");
        let mut echo = TW_TOOL;
        echo[..2].copy_from_slice(b"WT");
        let parsed = Reply::parse(&Message::new_checked(&echo[..]).unwrap()).unwrap();
        assert_eq!(parsed.command, Command::Twist);
    }

    #[test]
    fn undefined_index_bits_and_other_commands_are_refused() {
        let mut bad = TW_TOOL;
        bad[30] = 0x81;
        assert_eq!(Twist::parse(&request(&bad)), Err(VelocityError::BadIndex));
        let mut bad = JW_BANK_2;
        bad[30] = 0x01;
        assert_eq!(
            JointRates::parse(&request(&bad)),
            Err(VelocityError::BadIndex)
        );
        assert_eq!(
            Twist::parse(&request(&JW_BANK_2)),
            Err(VelocityError::WrongCommand)
        );
        assert_eq!(
            JointRates::parse(&request(&TW_TOOL)),
            Err(VelocityError::WrongCommand)
        );
    }
}
