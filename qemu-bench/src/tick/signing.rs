//! What signing costs (docs/protocol.md "Signed datagrams"): one signature check
//! (`Signature::parse`: HMAC-SHA256 from the key's precomputed states, two SHA-256
//! compressions, and the tag compared), one signing (`Signature::emit`, the same work), and the
//! tick that carries a signed `PS` with a key set (the check, the request, the signed answer),
//! and one write of the replay reservation ([`FlashLog`]'s `keep`, the board's store; at most
//! once per [`RESERVE_AHEAD`], 2 s, of the clients' timestamps): its instructions, on sectors
//! in RAM here (the board's flash programming time of one 32-byte word comes on top).

use core::hint::black_box;

use armgate_core::config::ValidRobot;
use armgate_core::cycle::{
    FlashLog, FlashSectors, RECORD_LEN, RESERVE_AHEAD, ReplayStore, Signing, UnsignedAccess,
};
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

/// The four measurements.
pub(super) struct Costs {
    pub verify: Timing,
    pub sign: Timing,
    pub pose: Timing,
    pub keep: Timing,
}

/// Records per sector of [`Ram`] (the board's sectors hold 4,096): room for every sample.
const RECORDS: usize = 64;

/// Two flash sectors in RAM: what the board's driver does, without the flash's own time.
struct Ram([[[u8; RECORD_LEN]; RECORDS]; 2]);

impl FlashSectors for Ram {
    fn records(&self) -> u32 {
        RECORDS as u32
    }
    fn read(&mut self, sector: u8, record: u32) -> Option<[u8; RECORD_LEN]> {
        let sector = self.0.get(usize::from(sector))?;
        sector.get(usize::try_from(record).ok()?).copied()
    }
    fn write(&mut self, sector: u8, record: u32, bytes: &[u8; RECORD_LEN]) -> bool {
        let word = usize::try_from(record)
            .ok()
            .and_then(|r| self.0.get_mut(usize::from(sector))?.get_mut(r));
        word.map(|w| *w = *bytes).is_some()
    }
    fn erase(&mut self, sector: u8) -> bool {
        let sector = self.0.get_mut(usize::from(sector));
        sector.map(|s| *s = [[0xff; RECORD_LEN]; RECORDS]).is_some()
    }
}

/// One reservation write per sample, each [`RESERVE_AHEAD`] above the last.
fn keep_costs() -> Result<Timing, &'static str> {
    let mut log = FlashLog::open(Ram([[[0xff; RECORD_LEN]; RECORDS]; 2]));
    let mut keep = Timing::default();
    for k in 1..=u64::from(SAMPLES) {
        let (ticks, kept) = measure(|| log.keep(black_box(k * RESERVE_AHEAD)));
        if !kept {
            return Err("a reservation was not kept");
        }
        keep.add(ticks);
    }
    Ok(keep)
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
        pose_ticks.add(session.exchange(&signature.emit(&pose, &key), b"SP")?.0);
        if session.link.answer.map(|a| a.payload().len()) != Some(SIGNED_LEN) {
            return Err("the answer to a signed PS was not signed");
        }
    }
    Ok(Costs {
        verify,
        sign,
        pose: pose_ticks,
        keep: keep_costs()?,
    })
}
