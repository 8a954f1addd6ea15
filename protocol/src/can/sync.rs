//! The SYNC object (COB-ID `0x080`, no data): the controller's cycle tick on the bus.
//!
//! Every drive whose transmit PDO has transmission type 1 sends it after each SYNC, with the
//! values sampled when the SYNC arrived (CiA 301).

use super::{CanFrame, Error};

/// The COB-ID of SYNC (CiA 301 default, object 0x1005).
pub const SYNC_ID: u16 = 0x080;

/// A SYNC frame: COB-ID 0x080, DLC 0 (this bus uses no SYNC counter).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SyncObject;

impl SyncObject {
    /// Decodes a SYNC frame.
    pub fn parse(frame: &CanFrame) -> Result<Self, Error> {
        if frame.id() != SYNC_ID {
            return Err(Error::WrongId);
        }
        if frame.dlc() != 0 {
            return Err(Error::WrongLength);
        }
        Ok(Self)
    }

    /// The frame.
    pub fn to_frame(&self) -> CanFrame {
        CanFrame::from_parts(SYNC_ID, 0, [0; 8])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sync_is_0x080_without_data() {
        let frame = SyncObject.to_frame();
        assert_eq!((frame.id(), frame.dlc(), frame.data()), (0x080, 0, &[][..]));
        assert_eq!(SyncObject::parse(&frame), Ok(SyncObject));
        let parse = |id, data: &[u8]| SyncObject::parse(&CanFrame::new(id, data).unwrap());
        assert_eq!(parse(0x081, &[]), Err(Error::WrongId));
        // A SYNC counter (CiA 301 object 0x1019) is not used on this bus.
        assert_eq!(parse(0x080, &[1]), Err(Error::WrongLength));
    }
}
