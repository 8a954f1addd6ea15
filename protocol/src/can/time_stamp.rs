//! The Time Stamp (COB-ID `0x100`, 4 bytes): the controller's microsecond clock at its last
//! SYNC, which locks the drives' motion clocks to the controller's.
//!
//! Elmo's CANopen DS 301 implementation guide (MAN-CAN301IG, chapter 8 "SYNC and Time Stamp"):
//! a drive latches its microsecond motion clock when a SYNC arrives; a Time Stamp, "a 32-bit
//! message that contains the master internal clock as generated upon receipt of the client's
//! own SYNC", always refers to the previous SYNC, and the drive adjusts its clock by the
//! difference, filtered ("about 200 SYNC-Time Stamp pairs" to full precision). COB-ID 0x100
//! is fixed on the drive (object 0x1012 cannot be changed). Byte order: little-endian, as
//! every CANopen value.

use super::{CanFrame, Error};

/// The COB-ID of the Time Stamp (CiA 301 default, object 0x1012; fixed on Elmo drives).
pub const TIME_STAMP_ID: u16 = 0x100;

/// A Time Stamp: the controller's clock (µs, wrapping at 2³²) when its last SYNC went out.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TimeStamp {
    /// Microseconds, counting up and wrapping (about 72 minutes a turn).
    pub micros: u32,
}

impl TimeStamp {
    /// Decodes a Time Stamp frame.
    pub fn parse(frame: &CanFrame) -> Result<Self, Error> {
        if frame.id() != TIME_STAMP_ID {
            return Err(Error::WrongId);
        }
        let bytes: [u8; 4] = frame.data().try_into().map_err(|_| Error::WrongLength)?;
        Ok(Self {
            micros: u32::from_le_bytes(bytes),
        })
    }

    /// The frame.
    pub fn to_frame(&self) -> CanFrame {
        let [a, b, c, d] = self.micros.to_le_bytes();
        CanFrame::from_parts(TIME_STAMP_ID, 4, [a, b, c, d, 0, 0, 0, 0])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_time_stamp_is_0x100_with_four_little_endian_bytes() {
        let stamp = TimeStamp {
            micros: 0x1234_5678,
        };
        let frame = stamp.to_frame();
        assert_eq!(
            (frame.id(), frame.data()),
            (0x100, &[0x78, 0x56, 0x34, 0x12][..])
        );
        assert_eq!(TimeStamp::parse(&frame), Ok(stamp));
        let parse = |id, data: &[u8]| TimeStamp::parse(&CanFrame::new(id, data).unwrap());
        assert_eq!(
            parse(0x100, &[0xFF, 0xFF, 0xFF, 0xFF]),
            Ok(TimeStamp { micros: u32::MAX })
        );
        assert_eq!(parse(0x101, &[0, 0, 0, 0]), Err(Error::WrongId));
        // CiA 301's 6-byte TIME_OF_DAY is not what an Elmo drive takes.
        assert_eq!(parse(0x100, &[0; 6]), Err(Error::WrongLength));
        assert_eq!(parse(0x100, &[0; 3]), Err(Error::WrongLength));
    }
}
