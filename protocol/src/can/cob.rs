//! CANopen addressing: node IDs, function codes, and the messages addressed by them.

use super::{CanFrame, Error};

/// A CANopen node ID, 1..=127.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NodeId(u8);

impl NodeId {
    /// The node ID `id`, if it is in 1..=127.
    pub const fn new(id: u8) -> Option<Self> {
        match id {
            1..=127 => Some(Self(id)),
            _ => None,
        }
    }

    /// The ID as a number.
    pub const fn get(self) -> u8 {
        self.0
    }
}

/// The function code in the upper four bits of a COB-ID, for the services used here.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u16)]
pub enum Function {
    /// Emergency, from a node.
    Emcy = 0x080,
    /// TPDO2: the drives' interpreter replies.
    Tpdo2 = 0x280,
    /// RPDO2: interpreter commands to the drives.
    Rpdo2 = 0x300,
    /// TPDO3: the drives' synchronous feedback (PDO streaming).
    Tpdo3 = 0x380,
    /// RPDO3: PT points to the drives (PDO streaming).
    Rpdo3 = 0x400,
    /// SDO server to client (response).
    SdoResponse = 0x580,
    /// SDO client to server (request).
    SdoRequest = 0x600,
    /// Heartbeat (NMT error control), from a node.
    Heartbeat = 0x700,
}

impl Function {
    /// The COB-ID of this function for `node`.
    pub const fn cob_id(self, node: NodeId) -> u16 {
        self as u16 | node.0 as u16
    }

    /// The function and node of a COB-ID: the node is `id & 0x7F`, and must not be 0;
    /// [`Error::WrongId`] for node 0 or a function not used here (NMT, SYNC, TPDO1, ...).
    pub fn split(id: u16) -> Result<(Self, NodeId), Error> {
        let node = NodeId::new((id & 0x7F) as u8).ok_or(Error::WrongId)?;
        let function = match id & 0x780 {
            0x080 => Self::Emcy,
            0x280 => Self::Tpdo2,
            0x300 => Self::Rpdo2,
            0x380 => Self::Tpdo3,
            0x400 => Self::Rpdo3,
            0x580 => Self::SdoResponse,
            0x600 => Self::SdoRequest,
            0x700 => Self::Heartbeat,
            _ => return Err(Error::WrongId),
        };
        Ok((function, node))
    }
}

/// A message whose COB-ID is a [`Function`] code plus the node ID.
pub trait NodeMessage: Sized {
    /// The function code.
    const FUNCTION: Function;

    /// Decodes the data field of `frame`, ignoring its identifier.
    fn decode(frame: &CanFrame) -> Result<Self, Error>;

    /// The data length and the data bytes (zero past the length).
    fn encode(&self) -> (u8, [u8; 8]);

    /// The sending or addressed node, and the message; [`Error::WrongId`] if the frame's COB-ID
    /// is not this message's function code plus a node ID.
    fn parse(frame: &CanFrame) -> Result<(NodeId, Self), Error> {
        match Function::split(frame.id())? {
            (function, node) if function == Self::FUNCTION => Ok((node, Self::decode(frame)?)),
            _ => Err(Error::WrongId),
        }
    }

    /// The frame carrying this message to or from `node`.
    fn to_frame(&self, node: NodeId) -> CanFrame {
        let (len, data) = self.encode();
        CanFrame::from_parts(Self::FUNCTION.cob_id(node), len, data)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn node_ids() {
        assert_eq!(NodeId::new(0), None);
        assert_eq!(NodeId::new(128), None);
        assert_eq!(NodeId::new(127).map(NodeId::get), Some(127));
    }

    #[test]
    fn cob_ids_split_and_join() {
        let node = NodeId::new(101).unwrap();
        for function in [
            Function::Emcy,
            Function::Tpdo2,
            Function::Rpdo2,
            Function::Tpdo3,
            Function::Rpdo3,
            Function::SdoResponse,
            Function::SdoRequest,
            Function::Heartbeat,
        ] {
            assert_eq!(Function::split(function.cob_id(node)), Ok((function, node)));
        }
        assert_eq!(Function::cob_id(Function::Rpdo2, node), 0x365);
        assert_eq!(
            Function::split(0x2EA),
            Ok((Function::Tpdo2, NodeId::new(106).unwrap()))
        );
        // The node is the low 7 bits, whatever the function: 0x5E5 is node 101, not 0xE5.
        assert_eq!(Function::split(0x5E5), Ok((Function::SdoResponse, node)));
        assert_eq!(Function::split(0x000), Err(Error::WrongId)); // NMT
        assert_eq!(Function::split(0x080), Err(Error::WrongId)); // SYNC
        assert_eq!(Function::cob_id(Function::Rpdo3, node), 0x465);
        assert_eq!(Function::split(0x3E5), Ok((Function::Tpdo3, node)));
        assert_eq!(Function::split(0x1E5), Err(Error::WrongId)); // TPDO1: not used
    }
}
