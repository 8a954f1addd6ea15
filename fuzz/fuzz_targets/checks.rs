//! What both fuzz targets check of every datagram's answer and every unsolicited notice.

use armgate_protocol::client::{
    Command, Header, Hold, MESSAGE_LEN, MIN_LEN, Message, Notice, Reply, Request, TEXT_CAPACITY,
    Text,
};

/// The parsers on a datagram: what the handler must answer it with.
pub fn check_parsers(datagram: &[u8]) -> Result<Request, Notice> {
    let message = match Message::new_checked(datagram) {
        Ok(message) => message,
        Err(e) => {
            assert!(datagram.len() < MIN_LEN);
            return Err(Notice::from(e));
        }
    };
    assert!(datagram.len() >= MIN_LEN);
    // The client-side parsers, on whatever arrived.
    let _ = Reply::parse(&message);
    if let Ok(text) = Text::parse(&message) {
        let s = text.as_str();
        assert!(s.len() <= TEXT_CAPACITY);
        assert!(s.bytes().all(|b| b == b' ' || b.is_ascii_graphic()));
        check_text_bytes(&text.to_bytes());
    }
    let request = Request::parse(&message).map_err(Notice::from)?;
    let bytes = request.to_bytes();
    let mut original = [0u8; MESSAGE_LEN];
    for (o, b) in original.iter_mut().zip(datagram) {
        *o = *b;
    }
    assert_eq!(
        bytes, original,
        "request does not re-encode to its datagram"
    );
    Ok(request)
}

/// The handler's answer to one datagram.
pub fn check_reply(datagram: &[u8], expected: Result<Request, Notice>, reply: &[u8; MESSAGE_LEN]) {
    let request = match expected {
        Ok(request) => request,
        Err(notice) => {
            assert_eq!(
                reply,
                &notice.text().to_bytes(),
                "datagram {datagram:02x?}: wrong answer to a non-request"
            );
            return;
        }
    };
    let message = Message::new_checked(&reply[..]).expect("31 bytes");
    if let Ok(r) = Reply::parse(&message) {
        assert_eq!(
            r.command, request.command,
            "reply {reply:02x?} to another command than {request:?}"
        );
        assert!(
            r.values.iter().all(|v| v.is_finite()),
            "non-finite value in reply {r:?} to {request:?}"
        );
        // KG and KS answer with a configuration branch (docs/protocol.md): KG the one taken
        // (0..=7, 8 without a closed form), KS the k-th solution's (0..=7), 0xFF for none.
        let index_ok = match request.command {
            Command::IkGoal => r.index <= 8,
            Command::IkSolution => r.index < 8 || r.index == 0xFF,
            _ => r.index == 0 || r.index == request.index || r.index == request.index & 0x80,
        };
        assert!(index_ok, "reply index {} to {request:?}", r.index);
        return;
    }
    check_text_bytes(reply);
    // A refusal of this request, of the grammar: `ERnn Cmd XX <reason>` with a code that
    // answers requests, or `ER10`/`ER11` for OF/ON.
    let text = Text::parse(&message).expect("a text");
    let notice = read_back(&text);
    let refusal = matches!(
        notice,
        Notice::Rejected(..)
            | Notice::BadNumber(_)
            | Notice::BadIndex(_)
            | Notice::OutsideWorkspace(..)
            | Notice::BeyondJointLimit(..)
            | Notice::ArmDidNotStart(_)
            | Notice::ArmDidNotStop(_)
            | Notice::BranchBeyondLimits(_)
    );
    let refuses = Header::parse(&text).ok().and_then(|h| h.refuses());
    assert!(
        refusal && refuses == Some(request.command.chars()),
        "answer {text:?} to {request:?} is neither its reply nor one of its error texts"
    );
}

/// An unsolicited notice from the relay: a motion warning, a stop's notice (the client
/// watchdog's `ER41`, a following error's `ER43`: a drive that does not follow, or a position
/// report the fuzzer injected), or a drive fault (`ER3x`).
pub fn check_notice(bytes: &[u8; MESSAGE_LEN]) {
    check_text_bytes(bytes);
    let text = Text::parse(&Message::new_checked(&bytes[..]).expect("31 bytes")).expect("a text");
    if Header::parse(&text).is_ok_and(|h| h.is_drive_fault()) {
        return;
    }
    let notice = read_back(&text);
    let allowed = [
        Notice::JointLimit,
        Notice::WorkspaceLimit,
        Notice::IkDivergence,
        Notice::ViaPointMissed,
        Notice::Held(Hold::Workspace),
    ];
    // A stream held at a joint limit names the joint and the limit, one held before a link's
    // contact the link and the obstacle; stops name their time, their
    // joint and its lag, or (for the arm's body) the link and the obstacle.
    let named = matches!(
        notice,
        Notice::Held(Hold::JointLimit(_) | Hold::Contact(_))
            | Notice::ClientSilent(_)
            | Notice::FollowingError(_)
            | Notice::Collision(_)
    );
    assert!(
        named || allowed.contains(&notice),
        "unexpected unsolicited text {:?}",
        text.as_str()
    );
}

/// The notice a text of the controller's reads back as (protocol's grammar), which writes the
/// same text again.
fn read_back(text: &Text) -> Notice {
    let notice = Notice::parse(text)
        .unwrap_or_else(|e| panic!("text {:?} is not of the grammar: {e}", text.as_str()));
    assert_eq!(
        notice.text(),
        *text,
        "text {:?} reads back as another",
        text.as_str()
    );
    notice
}

/// `ER`/`WN`, two digits, a space, printable ASCII, a NUL, zeros to the end.
pub fn check_text_bytes(bytes: &[u8; MESSAGE_LEN]) {
    let end = bytes.iter().position(|&b| b == 0).expect("no NUL");
    assert!(end <= TEXT_CAPACITY, "text {bytes:02x?} too long");
    let (text, tail) = bytes.split_at(end);
    assert!(
        tail.iter().all(|&b| b == 0),
        "text {bytes:02x?} not zero-filled"
    );
    assert!(
        text.iter().all(|&b| b == b' ' || b.is_ascii_graphic()),
        "text {bytes:02x?} not printable"
    );
    assert!(
        text.starts_with(b"ER") || text.starts_with(b"WN"),
        "text {bytes:02x?} is neither ER nor WN"
    );
}
