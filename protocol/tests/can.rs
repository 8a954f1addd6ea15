//! The CAN frames against the spec's literal bytes (§6.3, §6.7), and against random frames.
// Helpers outside `#[test]` functions may unwrap too: a panic here is a failed test.
#![allow(clippy::unwrap_used)]

mod common;

use armgate_protocol::can::interpreter::{Index, Mnemonic, Reply, Request, Value};
use armgate_protocol::can::{
    CanFrame, Emcy, Error, Heartbeat, Incoming, Nmt, NmtState, NodeId, NodeMessage, Object,
    PtFeedback, PtPoint, SdoRequest, SdoResponse, SdoValue, SyncObject,
};
use common::XorShift;

const NODE: NodeId = match NodeId::new(101) {
    Some(node) => node,
    None => unreachable!(),
};

fn frame(id: u16, data: &[u8]) -> CanFrame {
    CanFrame::new(id, data).unwrap()
}

/// `request` to node 101 is exactly `data` on COB-ID 0x365, and parses back.
fn assert_request(request: Request, data: &[u8]) {
    let sent = request.to_frame(NODE);
    assert_eq!(sent, frame(0x365, data));
    assert_eq!(Request::parse(&sent), Ok((NODE, request)));
}

#[test]
fn interpreter_examples() {
    let set = |command, index: u8, value| Request::Set {
        command,
        index: index.into(),
        value,
    };
    let query = |command, index: u8| Request::Query {
        command,
        index: index.into(),
    };
    assert_request(
        set(Mnemonic::QP, 3, Value::Int(-12345)),
        &[0x51, 0x50, 0x03, 0x00, 0xC7, 0xCF, 0xFF, 0xFF],
    );
    assert_request(
        set(Mnemonic::MP, 4, Value::Int(54)),
        &[0x4D, 0x50, 0x04, 0x00, 0x36, 0x00, 0x00, 0x00],
    );
    assert_request(query(Mnemonic::PX, 0), &[0x50, 0x58, 0x00, 0x00]);
    assert_request(query(Mnemonic::TI, 1), &[0x54, 0x49, 0x01, 0x00]);
    assert_request(
        set(Mnemonic::TC, 0, Value::Float(1.5)),
        &[0x54, 0x43, 0x00, 0x80, 0x00, 0x00, 0xC0, 0x3F],
    );
    assert_request(query(Mnemonic::BG, 0), b"BG\0\0");
}

#[test]
fn interpreter_replies() {
    let classify = |data: &[u8]| Incoming::classify(&frame(0x2E5, data));
    let value = |command, index: u8, value| Incoming::Interpreter {
        node: NODE,
        reply: Reply::Value {
            command,
            index: index.into(),
            value,
        },
    };
    assert_eq!(
        classify(&[0x50, 0x58, 0, 0, 0xC7, 0xCF, 0xFF, 0xFF]),
        value(Mnemonic::PX, 0, Value::Int(-12345))
    );
    assert_eq!(
        classify(&[0x54, 0x49, 1, 0, 42, 0, 0, 0]),
        value(Mnemonic::TI, 1, Value::Int(42))
    );
    assert_eq!(
        classify(&[0x54, 0x43, 0, 0x80, 0, 0, 0xC0, 0x3F]),
        value(Mnemonic::TC, 0, Value::Float(1.5))
    );

    // Error flag (byte 3 bit 6), Elmo error code in byte 4.
    let error = Reply::Error {
        command: Mnemonic::QP,
        index: 3.into(),
        code: 0x15,
    };
    assert_eq!(
        classify(&[0x51, 0x50, 0x03, 0x40, 0x15, 0, 0, 0]),
        Incoming::Interpreter {
            node: NODE,
            reply: error
        }
    );
    assert_eq!(Reply::parse(&error.to_frame(NODE)), Ok((NODE, error)));

    // A reply too short to hold the header is reported, not dropped.
    let malformed = Incoming::Malformed {
        id: 0x2E5,
        error: Error::WrongLength,
    };
    assert_eq!(classify(&[0x51, 0x50, 0x03]), malformed);
}

#[test]
fn nmt_start_all() {
    assert_eq!(Nmt::START_ALL.to_frame(), frame(0x000, &[0x01, 0x00]));
    assert_eq!(Nmt::parse(&frame(0x000, &[0x01, 0x00])), Ok(Nmt::START_ALL));
    assert_eq!(
        Incoming::classify(&Nmt::START_ALL.to_frame()),
        Incoming::Other
    );
}

#[test]
fn emcy_and_the_hall_whitelist() {
    let hall = Incoming::classify(&frame(0x0E5, &[0x80, 0x83, 0x81, 0, 0, 0, 0, 0]));
    let Incoming::Emcy { node, emcy } = hall else {
        panic!("{hall:?}")
    };
    assert_eq!(node, NODE);
    assert_eq!((emcy.code, emcy.register), (0x8380, 0x81));
    assert!(emcy.is_digital_hall());

    let other = Emcy::decode(&frame(0x0E5, &[0x80, 0x83, 0x01, 0, 0, 0, 0, 0])).unwrap();
    assert!(!other.is_digital_hall());
    let queue_low = Emcy::decode(&frame(0x0E5, &[0x00, 0xFF, 0x01, 0x56, 1, 2, 3, 4])).unwrap();
    assert_eq!(
        queue_low,
        Emcy {
            code: 0xFF00,
            register: 1,
            manufacturer: [0x56, 1, 2, 3, 4]
        }
    );
    assert_eq!(
        Emcy::parse(&queue_low.to_frame(NODE)),
        Ok((NODE, queue_low))
    );
    // A short emergency still counts.
    assert!(matches!(
        Incoming::classify(&frame(0x0E5, &[0x10])),
        Incoming::Emcy { .. }
    ));
    // 0x080 is SYNC, not an emergency.
    assert_eq!(Incoming::classify(&frame(0x080, &[])), Incoming::Sync);
    assert_eq!(
        Incoming::classify(&frame(0x080, &[0])),
        Incoming::Malformed {
            id: 0x080,
            error: Error::WrongLength
        }
    );
}

#[test]
fn heartbeats() {
    let controller = NodeId::new(127).unwrap();
    let own = Heartbeat {
        state: NmtState::Operational,
    }
    .to_frame(controller);
    assert_eq!(own, frame(0x77F, &[0x05]));
    assert_eq!(
        Incoming::classify(&frame(0x765, &[0x00])),
        Incoming::Heartbeat {
            node: NODE,
            state: NmtState::BootUp
        }
    );
    assert_eq!(
        Incoming::classify(&frame(0x765, &[0x04])),
        Incoming::Heartbeat {
            node: NODE,
            state: NmtState::Stopped
        }
    );
}

#[test]
fn sdo_heartbeat_configuration() {
    // The drive expects the controller's (node 127) heartbeat at least every 100 ms.
    let controller = NodeId::new(127).unwrap();
    let consumer = SdoRequest::consumer_heartbeat(controller, 100).to_frame(NODE);
    assert_eq!(
        consumer,
        frame(0x665, &[0x23, 0x16, 0x10, 0x01, 0x64, 0x00, 0x7F, 0x00])
    );
    let producer = SdoRequest::producer_heartbeat(50).to_frame(NODE);
    assert_eq!(
        producer,
        frame(0x665, &[0x2B, 0x17, 0x10, 0x00, 0x32, 0x00, 0x00, 0x00])
    );
    assert_eq!(
        SdoRequest::parse(&producer),
        Ok((
            NODE,
            SdoRequest::Download {
                object: Object {
                    index: 0x1017,
                    subindex: 0
                },
                value: SdoValue::U16(50)
            }
        ))
    );

    let ack = Incoming::classify(&frame(0x5E5, &[0x60, 0x16, 0x10, 0x01, 0, 0, 0, 0]));
    let object = Object {
        index: 0x1016,
        subindex: 1,
    };
    assert_eq!(
        ack,
        Incoming::SdoResponse {
            node: NODE,
            response: SdoResponse::Downloaded { object }
        }
    );

    // The seed's RPDO3-mapping acknowledgement `60 02 16 01`: object 0x1602 sub 1.
    let mapping = SdoResponse::decode(&frame(0x5E5, &[0x60, 0x02, 0x16, 0x01, 0, 0, 0, 0]));
    assert_eq!(
        mapping,
        Ok(SdoResponse::Downloaded {
            object: Object {
                index: 0x1602,
                subindex: 1
            }
        })
    );

    let upload = SdoRequest::Upload {
        object: Object {
            index: 0x1018,
            subindex: 1,
        },
    }
    .to_frame(NODE);
    assert_eq!(upload, frame(0x665, &[0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0]));
    let vendor = Incoming::classify(&frame(
        0x5E5,
        &[0x43, 0x18, 0x10, 0x01, 0x9A, 0x00, 0x00, 0x00],
    ));
    let value = SdoValue::U32(0x9A);
    let response = SdoResponse::Uploaded {
        object: Object {
            index: 0x1018,
            subindex: 1,
        },
        value,
    };
    assert_eq!(
        vendor,
        Incoming::SdoResponse {
            node: NODE,
            response
        }
    );
}

#[test]
fn frames_for_others_are_not_ours() {
    // Commands to a drive (from us or another master), and SDO requests.
    assert_eq!(
        Incoming::classify(&frame(0x365, b"PX\0\0")),
        Incoming::Other
    );
    assert_eq!(
        Incoming::classify(&frame(0x665, &[0x40, 0, 0x10, 0, 0, 0, 0, 0])),
        Incoming::Other
    );
    assert_eq!(
        Request::parse(&frame(0x2E5, b"PX\0\0")),
        Err(Error::WrongId)
    );
    assert_eq!(Reply::parse(&frame(0x300, b"PX\0\0")), Err(Error::WrongId)); // node 0
}

#[test]
fn index_high_bits() {
    let request = Request::Query {
        command: Mnemonic::QP,
        index: Index::new(1000).unwrap(),
    };
    assert_request(request, &[0x51, 0x50, 0xE8, 0x03]);
}

/// Decoding `frame` as `M`, encoding and decoding again gives the same message (compared by
/// encoding, so that NaN floats compare bit by bit).
fn assert_reencodes<M: NodeMessage>(frame: &CanFrame) {
    if let Ok((node, message)) = M::parse(frame) {
        let again = M::parse(&message.to_frame(node)).map(|(node, m)| (node, m.encode()));
        assert_eq!(again, Ok((node, message.encode())));
    }
}

#[test]
fn random_frames_never_panic_and_reencode() {
    let mut rng = XorShift(0x2545_F491_4F6C_DD1D);
    let ids = [
        0x000, 0x080, 0x280, 0x300, 0x380, 0x400, 0x580, 0x600, 0x700,
    ];
    let specifiers = [
        0x00, 0x01, 0x05, 0x7F, 0x85, 0x23, 0x27, 0x2B, 0x2F, 0x40, 0x43, 0x4F, 0x60, 0x80,
    ];
    let (mut requests, mut replies) = (0, 0);
    for case in 0..100_000 {
        let id = if case % 2 == 0 {
            ids[case % ids.len()] | (rng.next() as u16 & 0x7F)
        } else {
            rng.next() as u16 & 0x7FF
        };
        let mut data = rng.next().to_le_bytes();
        // Make well-formed headers frequent.
        match case % 4 {
            0 => data[..2].copy_from_slice(&[
                b'A' + (rng.next() % 26) as u8,
                b'A' + (rng.next() % 26) as u8,
            ]),
            1 => data[0] = specifiers[(rng.next() % 14) as usize],
            _ => {}
        }
        if rng.next().is_multiple_of(2) {
            data[3] &= !0x40;
        }
        let frame = CanFrame::new(id, &data[..(rng.next() % 9) as usize]).unwrap();
        if let Incoming::Interpreter { node, reply } = Incoming::classify(&frame) {
            replies += 1;
            if matches!(reply, Reply::Value { .. }) && frame.dlc() == 8 {
                assert_eq!(reply.to_frame(node), frame);
            }
        }
        if let Ok((node, request)) = Request::parse(&frame) {
            requests += 1;
            assert_eq!(request.to_frame(node), frame);
        }
        let _ = Nmt::parse(&frame);
        if SyncObject::parse(&frame).is_ok() {
            assert_eq!(SyncObject.to_frame(), frame);
        }
        if let Ok((node, point)) = PtPoint::parse(&frame) {
            assert_eq!(point.to_frame(node), frame);
        }
        if let Ok((node, feedback)) = PtFeedback::parse(&frame) {
            assert_eq!(feedback.to_frame(node), frame);
        }
        assert_reencodes::<Request>(&frame);
        assert_reencodes::<Reply>(&frame);
        assert_reencodes::<Emcy>(&frame);
        assert_reencodes::<Heartbeat>(&frame);
        assert_reencodes::<SdoRequest>(&frame);
        assert_reencodes::<SdoResponse>(&frame);
    }
    assert!(
        requests > 300 && replies > 300,
        "{requests} requests, {replies} replies"
    );
}
