//! A classic CAN data frame with a standard identifier.

use super::Error;

/// The largest standard (11-bit) identifier.
pub const MAX_ID: u16 = 0x7FF;

/// The most data bytes of a classic CAN frame.
pub const MAX_DLC: u8 = 8;

/// A data frame: an 11-bit identifier and 0..=8 data bytes. The data bytes past the length are
/// always zero, so decoders may read all eight.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CanFrame {
    id: u16,
    len: u8,
    data: [u8; 8],
}

impl CanFrame {
    /// A frame, checking the identifier (at most [`MAX_ID`]) and the length (at most 8 bytes).
    pub fn new(id: u16, data: &[u8]) -> Result<Self, Error> {
        if id > MAX_ID {
            return Err(Error::IdOutOfRange);
        }
        let len = u8::try_from(data.len())
            .ok()
            .filter(|&len| len <= MAX_DLC)
            .ok_or(Error::TooLong)?;
        let mut bytes = [0; 8];
        bytes.iter_mut().zip(data).for_each(|(o, b)| *o = *b);
        Ok(Self {
            id,
            len,
            data: bytes,
        })
    }

    /// A frame from parts that the crate's encoders keep valid; out-of-range parts are clipped
    /// rather than trusted, so the invariants hold whatever is passed.
    pub(crate) fn from_parts(id: u16, len: u8, mut data: [u8; 8]) -> Self {
        let len = len.min(MAX_DLC);
        data.iter_mut().skip(usize::from(len)).for_each(|b| *b = 0);
        Self {
            id: id & MAX_ID,
            len,
            data,
        }
    }

    /// The 11-bit identifier (COB-ID).
    pub const fn id(&self) -> u16 {
        self.id
    }

    /// The data length code, 0..=8.
    pub const fn dlc(&self) -> u8 {
        self.len
    }

    /// The data bytes.
    pub fn data(&self) -> &[u8] {
        self.data.get(..usize::from(self.len)).unwrap_or_default()
    }

    /// All eight data bytes; those past [`dlc`](Self::dlc) are zero.
    pub const fn raw_data(&self) -> &[u8; 8] {
        &self.data
    }
}

/// The worst-case number of bits `frame` occupies on the bus: 47 + 8·n bits including the 3-bit
/// interframe space, plus at most ⌊(34 + 8·n − 1)/4⌋ stuff bits in the 34 + 8·n bits from
/// start-of-frame to the end of the CRC.
pub fn bits_on_wire(frame: &CanFrame) -> u32 {
    let data_bits = 8 * u32::from(frame.dlc());
    47 + data_bits + (34 + data_bits - 1) / 4
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checked_constructor() {
        assert_eq!(CanFrame::new(0x800, &[]), Err(Error::IdOutOfRange));
        assert_eq!(CanFrame::new(0x7FF, &[0; 9]), Err(Error::TooLong));
        let frame = CanFrame::new(0x7FF, &[1, 2, 3]).unwrap();
        assert_eq!(
            (frame.id(), frame.dlc(), frame.data()),
            (0x7FF, 3, &[1, 2, 3][..])
        );
        assert_eq!(frame.raw_data(), &[1, 2, 3, 0, 0, 0, 0, 0]);
    }

    #[test]
    fn from_parts_clips() {
        let frame = CanFrame::from_parts(0xFFFF, 9, [0xAA; 8]);
        assert_eq!((frame.id(), frame.dlc()), (0x7FF, 8));
        let frame = CanFrame::from_parts(0x123, 2, [0xAA; 8]);
        assert_eq!(frame.raw_data(), &[0xAA, 0xAA, 0, 0, 0, 0, 0, 0]);
    }

    #[test]
    fn worst_case_bits() {
        let bits = |n: usize| bits_on_wire(&CanFrame::new(0x123, &[0; 8][..n]).unwrap());
        assert_eq!(bits(0), 55);
        assert_eq!(bits(4), 47 + 32 + 16);
        assert_eq!(bits(8), 135);
    }
}
