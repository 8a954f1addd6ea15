//! The client protocol against the spec's literal bytes (§2), and against random datagrams.
// Helpers outside `#[test]` functions may unwrap too: a panic here is a failed test.
#![allow(clippy::unwrap_used)]

mod common;

use armgate_protocol::client::{
    Command, DecodeError, DriveStatus, Error, JointBound, MESSAGE_LEN, Message, Notice, PathPoint,
    Rejection, Reply, Request, Severity, Text,
};
use common::XorShift;

/// `GT` to x = 0.5, y = 0.2, z = 0.1 m, roll = pitch = yaw = 0, T = 5 s (spec §2.9).
const GT: [u8; MESSAGE_LEN] = [
    0x47, 0x54, 0x00, 0x00, 0x00, 0x3F, 0xCD, 0xCC, 0x4C, 0x3E, 0xCD, 0xCC, 0xCC, 0x3D, 0x00, 0x00,
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xA0, 0x40, 0x00,
];

/// `VP` via point 3 = (0.5, -0.2, 0.4) m, yaw -1.5708, T = 2 s (spec §2.9).
const VP: [u8; MESSAGE_LEN] = [
    0x56, 0x50, 0x00, 0x00, 0x00, 0x3F, 0xCD, 0xCC, 0x4C, 0xBE, 0xCD, 0xCC, 0xCC, 0x3E, 0x00, 0x00,
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xF9, 0x0F, 0xC9, 0xBF, 0x00, 0x00, 0x00, 0x40, 0x03,
];

/// `bytes` followed by zeros.
fn padded(bytes: &[u8]) -> [u8; MESSAGE_LEN] {
    let mut out = [0; MESSAGE_LEN];
    out.iter_mut().zip(bytes).for_each(|(o, b)| *o = *b);
    out
}

fn parse(datagram: &[u8]) -> Result<Request, Error> {
    Message::new_checked(datagram).and_then(|message| Request::parse(&message))
}

#[test]
fn goal_rpy_example() {
    let request = parse(&GT).unwrap();
    let values = [0.5, 0.2, 0.1, 0.0, 0.0, 0.0, 5.0];
    assert_eq!(
        request,
        Request {
            command: Command::GoalRpy,
            values,
            index: 0
        }
    );
    assert_eq!(request.to_bytes(), GT);

    let mut tg = GT;
    tg[..2].copy_from_slice(&[0x54, 0x47]);
    assert_eq!(
        Reply {
            command: Command::GoalRpy,
            values,
            index: 0
        }
        .to_bytes(),
        tg
    );
}

#[test]
#[allow(clippy::approx_constant)] // The spec's yaw is 1.5708 (F9 0F C9 BF), not π/2 (DB 0F C9 BF).
fn via_point_example_keeps_the_index() {
    let request = parse(&VP).unwrap();
    let values = [0.5, -0.2, 0.4, 0.0, 0.0, -1.5708, 2.0];
    assert_eq!(
        request,
        Request {
            command: Command::ViaPoint,
            values,
            index: 3
        }
    );

    let mut pv = VP;
    pv[..2].copy_from_slice(&[0x50, 0x56]);
    let reply = Reply {
        command: Command::ViaPoint,
        values,
        index: 3,
    };
    assert_eq!(reply.to_bytes(), pv);
    assert_eq!(
        Reply::parse(&Message::new_checked(&pv[..]).unwrap()),
        Ok(reply)
    );
}

#[test]
fn change_mode_and_begin_examples() {
    let cm = padded(&[0x43, 0x4D, 0x00, 0x00, 0x00, 0x40]);
    let request = parse(&cm).unwrap();
    assert_eq!(
        (request.command, request.values[0], request.index),
        (Command::ChangeMode, 2.0, 0)
    );
    let reply = Reply {
        command: Command::ChangeMode,
        values: [2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        index: 0,
    };
    assert_eq!(
        reply.to_bytes(),
        padded(&[0x4D, 0x43, 0x00, 0x00, 0x00, 0x40])
    );

    assert_eq!(
        Reply::null(Command::Begin).to_bytes(),
        padded(&[0x47, 0x42])
    );
}

#[test]
fn thirty_bytes_mean_index_zero() {
    let mut vp = VP;
    vp[30] = 0;
    assert_eq!(parse(&VP[..30]), Ok(parse(&vp).unwrap()));
}

#[test]
fn undersized_datagrams_carry_the_bytes_present() {
    assert_eq!(parse(&[]), Err(Error::Undersized(*b"??")));
    assert_eq!(parse(b"G"), Err(Error::Undersized(*b"G?")));
    assert_eq!(parse(b"GT"), Err(Error::Undersized(*b"GT")));
    assert_eq!(parse(&GT[..29]), Err(Error::Undersized(*b"GT")));

    let answer = Notice::from(Error::Undersized(*b"G?")).text().to_bytes();
    assert_eq!(answer, padded(b"ER01 Msg G? undersized."));
}

#[test]
fn longer_datagrams_are_truncated_to_31_bytes() {
    for len in [32, 100] {
        let mut long = [0xEE; 100];
        long[..MESSAGE_LEN].copy_from_slice(&VP);
        let message = Message::new_checked(&long[..len]).unwrap();
        assert_eq!(message.bytes(), VP);
        assert_eq!(Request::parse(&message), parse(&VP));
    }
}

#[test]
fn unknown_commands_are_named() {
    let mut jv = VP;
    jv[..2].copy_from_slice(b"JV");
    assert_eq!(parse(&jv), Err(Error::UnknownCommand(*b"JV")));
    let answer = Notice::from(Error::UnknownCommand(*b"JV"))
        .text()
        .to_bytes();
    assert_eq!(answer, padded(b"ER00 Cmd JV not understood"));
    // A reply is not a request.
    assert_eq!(parse(&padded(b"GB")), Err(Error::UnknownCommand(*b"GB")));
}

#[test]
fn texts_are_zero_filled_over_stale_bytes() {
    for notice in [
        Notice::Rejected(Command::Begin, Rejection::Busy),
        Notice::JointLimit,
    ] {
        let mut buffer = [0xFF; MESSAGE_LEN];
        let mut message = Message::new_checked(&mut buffer[..]).unwrap();
        notice.text().emit(&mut message);
        let text = notice.text();
        assert_eq!(buffer, padded(text.as_str().as_bytes()));
        assert_eq!(
            Text::parse(&Message::new_checked(&buffer[..]).unwrap()),
            Ok(text)
        );
    }
    assert_eq!(Notice::JointLimit.text().severity(), Severity::Warning);
    assert_eq!(
        Text::parse(&Message::new_checked(&GT[..]).unwrap()),
        Err(DecodeError::WrongCommand)
    );
}

#[test]
fn emit_into_a_thirty_byte_buffer_drops_only_the_index() {
    let mut buffer = [0; 30];
    Request::parse(&Message::new_checked(&VP[..]).unwrap())
        .unwrap()
        .emit(&mut Message::new_checked(&mut buffer[..]).unwrap());
    assert_eq!(buffer, VP[..30]);
}

#[test]
fn requests_and_replies_round_trip_bit_exactly() {
    let mut rng = XorShift(0x1234_5678_9ABC_DEF0);
    for _ in 0..10_000 {
        let command = Command::ALL[rng.next() as usize % Command::ALL.len()];
        let values = std::array::from_fn(|_| f32::from_bits(rng.next() as u32));
        let index = rng.next() as u8;
        let request = Request {
            command,
            values,
            index,
        };
        let bytes = request.to_bytes();
        let back = Request::parse(&Message::new_checked(&bytes[..]).unwrap()).unwrap();
        assert_eq!(back.to_bytes(), bytes);
        assert_eq!((back.command, back.index), (command, index));
        assert_eq!(back.values.map(f32::to_bits), values.map(f32::to_bits));

        let reply = Reply {
            command,
            values,
            index,
        };
        let bytes = reply.to_bytes();
        let back = Reply::parse(&Message::new_checked(&bytes[..]).unwrap()).unwrap();
        assert_eq!(back.to_bytes(), bytes);
        assert_eq!((back.command, back.index), (command, index));
    }
}

#[test]
fn random_datagrams_never_panic() {
    let mut rng = XorShift(0x9E37_79B9_7F4A_7C15);
    let mut buffer = [0; 40];
    for case in 0..100_000 {
        let datagram = &mut buffer[..case % 41];
        rng.fill(datagram);
        // Make known commands and texts frequent.
        if case % 3 == 0 && datagram.len() >= 2 {
            let chars = match rng.next() % 4 {
                0 => *b"ER",
                1 => *b"WN",
                n => Command::ALL[(rng.next() as usize) % 20]
                    .chars()
                    .map(|c| c ^ (n as u8 & 1)),
            };
            datagram[..2].copy_from_slice(&chars);
        }
        let datagram = &*datagram;
        match Message::new_checked(datagram) {
            Err(error) => {
                assert!(datagram.len() < 30);
                let text = Notice::from(error).text();
                assert!(text.as_str().starts_with("ER01 Msg "));
            }
            Ok(message) => {
                let expected = padded(&datagram[..datagram.len().min(MESSAGE_LEN)]);
                assert_eq!(message.bytes(), expected);
                match Request::parse(&message) {
                    Ok(request) => assert_eq!(request.to_bytes(), expected),
                    Err(error) => {
                        assert_eq!(error, Error::UnknownCommand(message.command()));
                        assert_eq!(Notice::from(error).text().as_str().len(), 26);
                    }
                }
                if let Ok(reply) = Reply::parse(&message) {
                    assert_eq!(reply.to_bytes(), expected);
                }
                if let Ok(text) = Text::parse(&message) {
                    let bytes = text.to_bytes();
                    assert!(text.as_str().len() < MESSAGE_LEN && bytes[MESSAGE_LEN - 1] == 0);
                    assert!(
                        text.as_str()
                            .bytes()
                            .all(|b| b == b' ' || b.is_ascii_graphic())
                    );
                    assert!(text.as_str().starts_with("ER") || text.as_str().starts_with("WN"));
                }
            }
        }
    }
}

#[test]
fn refusals_carry_their_reason_after_the_seed_prefix() {
    let starting = Notice::Rejected(Command::Begin, Rejection::Drives(DriveStatus::Starting));
    assert_eq!(
        starting.text().to_bytes(),
        padded(b"ER20 Cmd BG drives starting")
    );
    let j5 = Notice::BeyondJointLimit(
        Command::JointGoal,
        JointBound::new(4, false, 0.785, PathPoint::Goal),
    );
    assert_eq!(j5.text().to_bytes(), padded(b"ER26 Cmd jG j5 < 0.785"));
    // The longest reason still fits, NUL included.
    let longest = Notice::BeyondJointLimit(
        Command::ViaExecute,
        JointBound::new(7, false, -2.35, PathPoint::Along(99)),
    );
    let bytes = longest.text().to_bytes();
    assert_eq!(bytes, padded(b"ER26 Cmd VE j8 < -2.350 at 99%"));
    assert_eq!(bytes[30], 0);
}
