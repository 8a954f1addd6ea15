//! Network management: NMT commands (COB-ID 0), node states and heartbeats (`0x700 + node`).

use super::{CanFrame, Error, Function, NodeId, NodeMessage};

/// The COB-ID of NMT commands.
const NMT_ID: u16 = 0x000;

/// An NMT command specifier.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum NmtCommand {
    /// Start remote node: enter operational.
    Start = 0x01,
    /// Stop remote node.
    Stop = 0x02,
    /// Enter pre-operational.
    EnterPreOperational = 0x80,
    /// Reset the node's application.
    ResetNode = 0x81,
    /// Reset the node's communication.
    ResetCommunication = 0x82,
}

/// An NMT command frame: COB-ID 0, DLC 2, command specifier and node (0 = all nodes).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Nmt {
    /// What to do.
    pub command: NmtCommand,
    /// The node addressed; `None` addresses all nodes.
    pub node: Option<NodeId>,
}

impl Nmt {
    /// "Start remote node", all nodes (`01 00`): without it the drives do not answer.
    pub const START_ALL: Self = Self {
        command: NmtCommand::Start,
        node: None,
    };

    /// Decodes an NMT command frame.
    pub fn parse(frame: &CanFrame) -> Result<Self, Error> {
        if frame.id() != NMT_ID {
            return Err(Error::WrongId);
        }
        let [command, node, ..] = *frame.raw_data();
        if frame.dlc() != 2 {
            return Err(Error::WrongLength);
        }
        let command = match command {
            0x01 => NmtCommand::Start,
            0x02 => NmtCommand::Stop,
            0x80 => NmtCommand::EnterPreOperational,
            0x81 => NmtCommand::ResetNode,
            0x82 => NmtCommand::ResetCommunication,
            _ => return Err(Error::Malformed),
        };
        let node = match node {
            0 => None,
            id => Some(NodeId::new(id).ok_or(Error::Malformed)?),
        };
        Ok(Self { command, node })
    }

    /// The frame.
    pub fn to_frame(&self) -> CanFrame {
        let node = self.node.map_or(0, NodeId::get);
        CanFrame::from_parts(NMT_ID, 2, [self.command as u8, node, 0, 0, 0, 0, 0, 0])
    }
}

/// A node's NMT state, as its heartbeat reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum NmtState {
    /// Boot-up: the node has just (re)started.
    BootUp = 0x00,
    /// Stopped.
    Stopped = 0x04,
    /// Operational.
    Operational = 0x05,
    /// Pre-operational.
    PreOperational = 0x7F,
}

/// A heartbeat: DLC 1, the sender's NMT state. The controller also produces its own.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Heartbeat {
    /// The sender's state.
    pub state: NmtState,
}

impl NodeMessage for Heartbeat {
    const FUNCTION: Function = Function::Heartbeat;

    /// Ignores bit 7 (the toggle bit of node-guarding replies, which share the COB-ID).
    fn decode(frame: &CanFrame) -> Result<Self, Error> {
        let [state, ..] = *frame.raw_data();
        if frame.dlc() != 1 {
            return Err(Error::WrongLength);
        }
        let state = match state & 0x7F {
            0x00 => NmtState::BootUp,
            0x04 => NmtState::Stopped,
            0x05 => NmtState::Operational,
            0x7F => NmtState::PreOperational,
            _ => return Err(Error::Malformed),
        };
        Ok(Self { state })
    }

    fn encode(&self) -> (u8, [u8; 8]) {
        (1, [self.state as u8, 0, 0, 0, 0, 0, 0, 0])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nmt_round_trip_and_errors() {
        let node = NodeId::new(5);
        let nmt = Nmt {
            command: NmtCommand::ResetCommunication,
            node,
        };
        assert_eq!(nmt.to_frame().data(), &[0x82, 5]);
        assert_eq!(Nmt::parse(&nmt.to_frame()), Ok(nmt));
        let parse = |id, data: &[u8]| Nmt::parse(&CanFrame::new(id, data).unwrap());
        assert_eq!(parse(0x001, &[1, 0]), Err(Error::WrongId));
        assert_eq!(parse(0x000, &[1]), Err(Error::WrongLength));
        assert_eq!(parse(0x000, &[3, 0]), Err(Error::Malformed));
        assert_eq!(parse(0x000, &[1, 128]), Err(Error::Malformed));
    }

    #[test]
    fn heartbeat_states() {
        let decode = |data: &[u8]| Heartbeat::decode(&CanFrame::new(0x701, data).unwrap());
        assert_eq!(
            decode(&[0x85]),
            Ok(Heartbeat {
                state: NmtState::Operational
            })
        );
        assert_eq!(
            decode(&[0x7F]),
            Ok(Heartbeat {
                state: NmtState::PreOperational
            })
        );
        assert_eq!(decode(&[0x01]), Err(Error::Malformed));
        assert_eq!(decode(&[0x05, 0]), Err(Error::WrongLength));
    }
}
