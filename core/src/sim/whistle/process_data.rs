//! The simulated Whistle's process data and configuration: the SYNC and its TPDO3, RPDO3 points
//! into the PT table, and the SDO transfers that map them.

use super::*;

impl SimWhistle {
    /// A SYNC has arrived: a synchronous RPDO's point is applied, and a synchronous TPDO3
    /// reports the values at this instant.
    pub(super) fn sync(&mut self) {
        self.stats.syncs = self.stats.syncs.wrapping_add(1);
        if let Some(point) = self.deferred_point.take() {
            self.receive_point(point);
        }
        let tpdo = self.pdo.tpdo3;
        if !tpdo.valid() || tpdo.transmission != SYNCHRONOUS {
            return;
        }
        if self.faults.skip_tpdos > 0 {
            if self.faults.skip_tpdos != u32::MAX {
                self.faults.skip_tpdos -= 1;
            }
            self.stats.tpdos_skipped = self.stats.tpdos_skipped.wrapping_add(1);
            return;
        }
        let values = Sampled {
            position: self.position(),
            head: self.table.write_pointer(),
            tail: self.table.read_index(),
        };
        let data = tpdo_payload(&tpdo, values);
        if let Ok(frame) = CanFrame::new(tpdo.id(), &data) {
            self.stats.tpdos_sent = self.stats.tpdos_sent.wrapping_add(1);
            let ready = self.now + seconds_to_ns(self.config.sync_response);
            self.emit(frame, ready);
        }
    }

    /// An RPDO3 frame: its point goes to the PT table at the next sample, or at the first
    /// sample after the next SYNC for a synchronous RPDO.
    pub(super) fn rpdo3(&mut self, frame: &CanFrame) {
        match pdo::rpdo_content(&self.pdo.rpdo3, frame.data()) {
            RpdoContent::Point(point) if self.pdo.rpdo3.transmission == SYNCHRONOUS => {
                self.deferred_point = Some(point);
            }
            RpdoContent::Point(point) => self.receive_point(point),
            RpdoContent::NotMapped => {
                self.stats.pdo_errors = self.stats.pdo_errors.wrapping_add(1);
                self.inject(DriveEmergency::PdoNotMapped {
                    cob_id: self.pdo.rpdo3.id(),
                });
            }
            RpdoContent::TooShort => {
                self.stats.pdo_errors = self.stats.pdo_errors.wrapping_add(1);
                self.inject(DriveEmergency::Other(Emcy {
                    code: PDO_LENGTH_ERROR,
                    register: COMMUNICATION_REGISTER,
                    manufacturer: [0; 5],
                }));
            }
        }
    }

    /// A PT point received by PDO: the drive takes it at its next sample (ASSUMED: PDOs are
    /// handled in the position loop's rhythm). More than fit are lost, as interpreter
    /// commands are.
    pub(super) fn receive_point(&mut self, point: i32) {
        if self.received_points.push_back(point).is_err() {
            self.stats.commands_lost += 1;
            self.inject(DriveEmergency::MessageLost);
        }
    }

    /// A received PT point, written at the table's write pointer.
    pub(super) fn write_point(&mut self, point: i32) {
        match self.table.push(point, self.now) {
            Ok(()) => self.stats.pdo_points = self.stats.pdo_points.wrapping_add(1),
            Err(PushError::QueueFull { write }) => {
                self.stats.overflows += 1;
                self.inject(DriveEmergency::QueueFull { index: write });
            }
            Err(PushError::OutOfRange { write }) => {
                self.stats.pdo_errors = self.stats.pdo_errors.wrapping_add(1);
                self.inject(DriveEmergency::WritePointerOutOfRange { write });
            }
        }
    }

    /// An SDO request: the consumer heartbeat entry, and the PDO objects.
    pub(super) fn sdo(&mut self, request: SdoRequest) {
        let response = match request {
            SdoRequest::Download { object, .. } if self.faults.refuse_object == Some(object) => {
                SdoResponse::Abort {
                    object,
                    code: sdo_abort::NOT_MAPPABLE,
                }
            }
            SdoRequest::Download { object, value } if PdoObjects::holds(object) => {
                match self.pdo.download(object, value) {
                    Ok(()) => SdoResponse::Downloaded { object },
                    Err(code) => SdoResponse::Abort { object, code },
                }
            }
            SdoRequest::Upload { object } if PdoObjects::holds(object) => {
                match self.pdo.upload(object) {
                    Ok(value) => SdoResponse::Uploaded { object, value },
                    Err(code) => SdoResponse::Abort { object, code },
                }
            }
            SdoRequest::Download {
                object: Object::CONSUMER_HEARTBEAT,
                value: SdoValue::U32(value),
            } => {
                let entry = ConsumerHeartbeat::from_value(value);
                let time_ns = u64::from(entry.time_ms) * 1_000_000;
                self.consumer = entry.producer.filter(|_| time_ns > 0).map(|p| (p, time_ns));
                self.last_beat = None;
                SdoResponse::Downloaded {
                    object: Object::CONSUMER_HEARTBEAT,
                }
            }
            SdoRequest::Upload {
                object: Object::CONSUMER_HEARTBEAT,
            } => {
                let value = self.consumer.map_or(0, |(producer, time_ns)| {
                    ConsumerHeartbeat {
                        producer: Some(producer),
                        time_ms: (time_ns / 1_000_000) as u16,
                    }
                    .to_value()
                });
                SdoResponse::Uploaded {
                    object: Object::CONSUMER_HEARTBEAT,
                    value: SdoValue::U32(value),
                }
            }
            SdoRequest::Download { object, .. } | SdoRequest::Upload { object } => {
                SdoResponse::Abort {
                    object,
                    code: sdo_abort::NO_OBJECT,
                }
            }
        };
        let ready = self.now + seconds_to_ns(self.config.interpreter_time);
        self.emit(response.to_frame(self.config.node), ready);
    }
}
