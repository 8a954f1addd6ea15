//! What signing costs (docs/protocol.md "Signed datagrams"): one signature check
//! (`Signature::parse`: HMAC-SHA256 from the key's precomputed states, two SHA-256
//! compressions, and the tag compared), one signing (`Signature::emit`, the same work), and the
//! tick that carries a signed `PS` with a key set (the check, the request, the signed answer).

use core::hint::black_box;

use armgate_core::config::ValidRobot;
use armgate_core::cycle::{Signing, UnsignedAccess};
use armgate_protocol::client::signed::{
    ControllerId, SIGNED_LEN, Signature, Signed, SigningKey,
};
use armgate_protocol::client::{Command, Request};

use super::Session;
use crate::counter::{Timing, measure};

/// Checks, signings and signed ticks measured.
const SAMPLES: u32 = 50;
/// The key (its value does not change the cost).
const KEY: [u8; 32] = [0x5a; 32];

/// The three measurements.
pub(super) struct Costs {
    pub verify: Timing,
    pub sign: Timing,
    pub pose: Timing,
}

/// Measures them on a session of `config` from `start`, holding.
pub(super) fn costs(config: &ValidRobot, start: Option<&[f64]>) -> Result<Costs, &'static str> {
    // For a controller: the tag covers its id as well (4 more bytes in the same SHA-256 block).
    let key = SigningKey::new(&KEY).for_controller(ControllerId(0x5eed_0001));
    let pose = Request {
        command: Command::Pose,
        values: [0.0; 7],
        index: 0,
    }
    .to_bytes();
    let mut verify = Timing::default();
    let mut sign = Timing::default();
    for k in 0..SAMPLES {
        let signature = Signature {
            link: 1,
            timestamp: u64::from(k) + 1,
        };
        let (ticks, bytes) = measure(|| black_box(signature).emit(black_box(&pose), &key));
        sign.add(ticks);
        let (ticks, checked) = measure(|| {
            Signed::new_checked(&black_box(bytes)[..])
                .and_then(|signed| Signature::parse(&signed, &key))
        });
        checked.map_err(|_| "a signature did not verify")?;
        verify.add(ticks);
    }
    let signing = Signing {
        key: Some(key.clone()),
        unsigned: UnsignedAccess::Refused,
    };
    let mut session = Session::with_signing(config, start, signing)?;
    let mut pose_ticks = Timing::default();
    for k in 0..SAMPLES {
        let signature = Signature {
            link: 1,
            timestamp: u64::from(k) + 1,
        };
        pose_ticks.add(session.exchange(&signature.emit(&pose, &key), b"SP")?);
        if session.link.answer.map(|a| a.payload().len()) != Some(SIGNED_LEN) {
            return Err("the answer to a signed PS was not signed");
        }
    }
    Ok(Costs {
        verify,
        sign,
        pose: pose_ticks,
    })
}
