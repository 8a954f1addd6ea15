//! Emergency messages (EMCY, `0x080 + node`).

use super::{CanFrame, Error, Function, NodeMessage};

/// An emergency message from a node.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Emcy {
    /// The emergency error code (bytes 0–1, little-endian); 0 = error reset.
    pub code: u16,
    /// The error register, object 0x1001 (byte 2).
    pub register: u8,
    /// Manufacturer-specific bytes 3–7.
    pub manufacturer: [u8; 5],
}

impl Emcy {
    /// The code and register the seed treated as a digital Hall sensor error and ignored
    /// (bytes `80 83 81`): code 0x8380, register 0x81.
    pub const fn is_digital_hall(&self) -> bool {
        self.code == 0x8380 && self.register == 0x81
    }
}

impl NodeMessage for Emcy {
    const FUNCTION: Function = Function::Emcy;

    /// Accepts any length, reading missing bytes as zero: a short emergency is still an
    /// emergency, and must not be dropped as malformed.
    fn decode(frame: &CanFrame) -> Result<Self, Error> {
        let [c0, c1, register, manufacturer @ ..] = *frame.raw_data();
        Ok(Self {
            code: u16::from_le_bytes([c0, c1]),
            register,
            manufacturer,
        })
    }

    fn encode(&self) -> (u8, [u8; 8]) {
        let [c0, c1] = self.code.to_le_bytes();
        let [m0, m1, m2, m3, m4] = self.manufacturer;
        (8, [c0, c1, self.register, m0, m1, m2, m3, m4])
    }
}
