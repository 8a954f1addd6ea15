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

/// The exact number of bits `frame` occupies on the bus, including the stuff bits its actual
/// content needs and the 3-bit interframe space: what a bus analyser would count, where
/// [`bits_on_wire`] is the worst case for any content of that length.
///
/// Stuffing covers start-of-frame through the CRC sequence (ISO 11898-1): after five equal bits
/// a complementary bit is inserted, and it starts the next run. The CRC is CRC-15/CAN.
pub fn exact_bits_on_wire(frame: &CanFrame) -> u32 {
    let mut stuffing = Stuffing::default();
    let mut crc = Crc15::default();
    let header = (u32::from(frame.id()) << 7) | u32::from(frame.dlc()); // ID, RTR, IDE, r0, DLC
    let sof_to_dlc = (0..19).rev().map(|bit| (header >> bit) & 1 == 1);
    let data = frame
        .data()
        .iter()
        .flat_map(|byte| (0..8).rev().map(move |bit| (byte >> bit) & 1 == 1));
    for bit in sof_to_dlc.chain(data) {
        crc.push(bit);
        stuffing.push(bit);
    }
    let checksum = crc.0;
    (0..15)
        .rev()
        .for_each(|bit| stuffing.push((checksum >> bit) & 1 == 1));
    // Stuffed part, then CRC delimiter, ACK slot and delimiter, end of frame, interframe space.
    stuffing.bits + 1 + 2 + 7 + 3
}

/// Counts the bits of the stuffed part of a frame, stuff bits included.
#[derive(Default)]
struct Stuffing {
    bits: u32,
    last: bool,
    run: u8,
}

impl Stuffing {
    fn push(&mut self, bit: bool) {
        self.bits += 1;
        if self.run > 0 && bit == self.last {
            self.run += 1;
        } else {
            self.last = bit;
            self.run = 1;
        }
        if self.run == 5 {
            self.bits += 1;
            self.last = !bit;
            self.run = 1;
        }
    }
}

/// CRC-15/CAN (polynomial 0x4599, initial value 0) over the unstuffed bits.
#[derive(Default)]
struct Crc15(u16);

impl Crc15 {
    fn push(&mut self, bit: bool) {
        let feedback = bit ^ (self.0 & 0x4000 != 0);
        self.0 = (self.0 << 1) & 0x7FFF;
        if feedback {
            self.0 ^= 0x4599;
        }
    }
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

    #[test]
    fn exact_bits_count_the_stuffing_of_the_content() {
        // ID 0, no data: 34 dominant bits and a zero CRC need a stuff bit after every fifth.
        let zeros = CanFrame::new(0, &[]).unwrap();
        assert_eq!(exact_bits_on_wire(&zeros), 47 + 6);
        // Never more than the worst case, never less than the unstuffed length.
        let mut seed = 0x1234_5678_u32;
        for n in 0..=8 {
            for _ in 0..200 {
                seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                let bytes = seed.to_le_bytes();
                let data = [bytes, bytes.map(|b| b.rotate_left(3))].concat();
                let frame = CanFrame::new((seed >> 21) as u16, &data[..n]).unwrap();
                let exact = exact_bits_on_wire(&frame);
                assert!(exact <= bits_on_wire(&frame), "{frame:?}");
                assert!(exact >= 47 + 8 * n as u32, "{frame:?}");
            }
        }
    }

    #[test]
    fn crc15_of_a_known_message() {
        // CRC-15/CAN check value: the CRC of ASCII "123456789" is 0x059E.
        let mut crc = Crc15::default();
        for byte in b"123456789" {
            (0..8)
                .rev()
                .for_each(|bit| crc.push((byte >> bit) & 1 == 1));
        }
        assert_eq!(crc.0, 0x059E);
    }
}
