//! The drive manager's frames received: each one's sender is its own COB-ID's node; answers,
//! emergencies, SDO responses and transmit PDOs update the drive, its link and the faults.

use armgate_protocol::can::interpreter::{Mnemonic, Reply, Value};
use armgate_protocol::can::{CanFrame, Incoming, MappingRefusal, NodeId, SdoResponse};

use super::DriveManager;
use crate::drives::drive::{Drive, Joint};
use crate::drives::emergency::{DriveEmergency, REASON_UNDERFLOW};
use crate::drives::fault::DriveFault;
use crate::drives::streaming::{FlowError, Stream};

impl DriveManager {
    /// One received frame. Its sender is its own COB-ID's node (the seed kept the previous
    /// frame's sender for unknown nodes and gave up on the cycle at an unknown SDO, spec §9
    /// item 33).
    pub(super) fn handle(&mut self, frame: &CanFrame) {
        match Incoming::classify(frame) {
            Incoming::Interpreter { node, reply } => self.on_reply(node, reply),
            Incoming::Emcy { node, emcy } => self.on_emergency(node, DriveEmergency::decode(&emcy)),
            Incoming::SdoResponse { node, response } => self.on_sdo(node, response),
            Incoming::Feedback { node, feedback } => self.on_feedback(node, feedback),
            // A drive's COB-ID carrying what does not decode: a drive misbehaving, counted
            // apart from what is merely of no interest.
            Incoming::Malformed { .. } => {
                self.stats.frames_malformed = self.stats.frames_malformed.saturating_add(1);
            }
            Incoming::Heartbeat { .. } | Incoming::Sync | Incoming::Other => self.ignored(),
        }
    }

    pub(super) fn ignored(&mut self) {
        self.stats.frames_ignored = self.stats.frames_ignored.saturating_add(1);
    }

    /// The joint and drive of `node`.
    pub(super) fn drive_mut(&mut self, node: NodeId) -> Option<(usize, &mut Drive)> {
        self.joints
            .iter_mut()
            .enumerate()
            .find_map(|(index, joint)| match joint {
                Joint::Real(drive) if drive.node == node => Some((index, drive)),
                _ => None,
            })
    }

    pub(super) fn on_reply(&mut self, node: NodeId, reply: Reply) {
        let cycle = self.cycle;
        let Some((joint, drive)) = self.drive_mut(node) else {
            self.ignored();
            return;
        };
        drive.link.heard(cycle);
        let fault = match reply {
            Reply::Error { command, code, .. } => Some(DriveFault::ErrorReply {
                joint,
                command,
                code,
            }),
            Reply::Value {
                command,
                index,
                value,
            } => {
                if let Some(at) = drive
                    .awaiting
                    .iter()
                    .position(|frame| frame.answered_by(command, index))
                {
                    drive.awaiting.swap_remove(at);
                }
                // Every command used here answers an integer; the seed read floats only for
                // TC and IQ, which position mode does not use.
                let value = match value {
                    Value::Int(v) => v,
                    Value::Float(_) => return,
                };
                match command {
                    Mnemonic::PX => drive.position = Some(value),
                    Mnemonic::TI => drive.temperature = Some(value),
                    Mnemonic::UM => drive.unit_mode = Some(value),
                    _ => {}
                }
                match (command, drive.stream.as_mut().and_then(Stream::interpreter)) {
                    (Mnemonic::PT, Some(stream)) => {
                        stream.read_index(value).err().map(|e| match e {
                            FlowError::Underflow => DriveFault::Underflow { joint },
                            FlowError::Overrun => DriveFault::Overrun { joint },
                        })
                    }
                    (Mnemonic::BG, _) if value != 0 => {
                        Some(DriveFault::BeginRefused { joint, value })
                    }
                    _ => None,
                }
            }
        };
        if let Some(fault) = fault {
            self.raise(fault);
        }
    }

    pub(super) fn on_emergency(&mut self, node: NodeId, emergency: DriveEmergency) {
        let Some((joint, _)) = self.drive_mut(node) else {
            self.ignored();
            return;
        };
        let count = |n: &mut u32| *n = n.saturating_add(1);
        // Only faults stop the arm. The seed stopped on every emergency but the Hall one,
        // including the queue-low warning it had armed itself (spec §9 item 35).
        let fault = match emergency {
            DriveEmergency::ErrorReset => return,
            DriveEmergency::DigitalHall => return count(&mut self.stats.hall_warnings),
            DriveEmergency::QueueLow { .. } => return count(&mut self.stats.queue_low_warnings),
            DriveEmergency::QueueFull { .. } => DriveFault::Overrun { joint },
            DriveEmergency::MotionTerminated {
                reason: REASON_UNDERFLOW,
                ..
            } => DriveFault::Underflow { joint },
            DriveEmergency::HeartbeatLost => DriveFault::HeartbeatLost { joint },
            DriveEmergency::MotionTerminated { .. }
            | DriveEmergency::MessageLost
            | DriveEmergency::WritePointerOutOfRange { .. }
            | DriveEmergency::PdoNotMapped { .. }
            | DriveEmergency::Other(_) => DriveFault::Emergency {
                joint,
                emcy: emergency.encode(),
            },
        };
        self.raise(fault);
    }

    pub(super) fn on_sdo(&mut self, node: NodeId, response: SdoResponse) {
        let (cycle, group) = (self.cycle, self.timing.group);
        let Some((joint, drive)) = self.drive_mut(node) else {
            self.ignored();
            return;
        };
        drive.link.heard(cycle);
        let mapping = drive.step.configuration(drive.node, group);
        let fault = match mapping {
            // An answer to this drive's mapping transfer: checked.
            Some((step, read_back)) if response.object() == step.object => {
                let checked = if read_back {
                    step.check_read_back(&response)
                } else {
                    step.check_write(&response)
                };
                match checked {
                    Ok(()) => {
                        drive.awaiting.clear();
                        None
                    }
                    Err(refusal) => Some(DriveFault::MappingRefused {
                        joint,
                        object: step.object,
                        code: match refusal {
                            MappingRefusal::Abort(code) => Some(code),
                            MappingRefusal::Mismatch { .. } | MappingRefusal::Unexpected => None,
                        },
                    }),
                }
            }
            _ => {
                let object = response.object();
                let Some(at) = drive
                    .awaiting
                    .iter()
                    .position(|frame| frame.answered_by_sdo(object))
                else {
                    // Not awaited: the answer to a mapping transfer after a fallback.
                    return self.ignored();
                };
                drive.awaiting.swap_remove(at);
                if let SdoResponse::Abort { code, .. } = response {
                    return self.raise(DriveFault::SdoAbort { joint, code });
                }
                None
            }
        };
        if let Some(fault) = fault {
            self.refuse_mapping(fault);
        }
    }
}
