//! Sorting the frames a controller receives.

use super::interpreter::Reply;
use super::{
    CanFrame, Emcy, Error, Function, Heartbeat, NmtState, NodeId, NodeMessage, PtFeedback, SYNC_ID,
    SdoResponse, SyncObject,
};

/// A received frame, by what it means to the controller.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Incoming {
    /// A drive's interpreter reply (TPDO2), possibly an error reply.
    Interpreter {
        /// The drive.
        node: NodeId,
        /// Its reply.
        reply: Reply,
    },
    /// An emergency message.
    Emcy {
        /// The sender.
        node: NodeId,
        /// The emergency.
        emcy: Emcy,
    },
    /// A heartbeat.
    Heartbeat {
        /// The sender.
        node: NodeId,
        /// Its NMT state.
        state: NmtState,
    },
    /// An SDO response.
    SdoResponse {
        /// The sender.
        node: NodeId,
        /// The response.
        response: SdoResponse,
    },
    /// A drive's synchronous feedback (TPDO3): position and PT pointers at the last SYNC.
    Feedback {
        /// The drive.
        node: NodeId,
        /// Its feedback.
        feedback: PtFeedback,
    },
    /// A SYNC (from another SYNC producer, or seen by a drive).
    Sync,
    /// A frame with the COB-ID of one of the kinds above that does not decode as one: reported,
    /// not dropped, so that a drive misbehaving does not go unnoticed.
    Malformed {
        /// The frame's COB-ID.
        id: u16,
        /// Why it does not decode.
        error: Error,
    },
    /// Anything else: NMT, other PDOs, other masters' requests.
    Other,
}

impl Incoming {
    /// Sorts `frame`. The node is always the low 7 bits of the COB-ID.
    pub fn classify(frame: &CanFrame) -> Self {
        if frame.id() == SYNC_ID {
            return SyncObject::parse(frame).map_or_else(
                |error| Self::Malformed { id: SYNC_ID, error },
                |SyncObject| Self::Sync,
            );
        }
        let Ok((function, node)) = Function::split(frame.id()) else {
            return Self::Other;
        };
        let decoded = match function {
            Function::Tpdo2 => Reply::decode(frame).map(|reply| Self::Interpreter { node, reply }),
            Function::Emcy => Emcy::decode(frame).map(|emcy| Self::Emcy { node, emcy }),
            Function::Heartbeat => {
                Heartbeat::decode(frame).map(|Heartbeat { state }| Self::Heartbeat { node, state })
            }
            Function::SdoResponse => {
                SdoResponse::decode(frame).map(|response| Self::SdoResponse { node, response })
            }
            Function::Tpdo3 => {
                PtFeedback::decode(frame).map(|feedback| Self::Feedback { node, feedback })
            }
            Function::Rpdo2 | Function::Rpdo3 | Function::SdoRequest => return Self::Other,
        };
        decoded.unwrap_or_else(|error| Self::Malformed {
            id: frame.id(),
            error,
        })
    }
}
