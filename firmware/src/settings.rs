//! Network and signing settings embedded at build time.
//!
//! `build.rs` reads `ARMGATE_IP`, `ARMGATE_GATEWAY`, `ARMGATE_PORT`, `ARMGATE_ALLOW`,
//! `ARMGATE_KEY_FILE`, `ARMGATE_CONTROLLER_ID` and `ARMGATE_ALLOW_UNSIGNED` and writes the constants below
//! (`OUT_DIR/settings.rs`); a malformed value fails the build. Defaults: `192.168.1.50/24`,
//! no gateway, port 7031, allow-list `local` (the board's own network), no key. See
//! `docs/firmware.md`.

use core::net::Ipv4Addr;

pub use armgate_core::command::Network;
use armgate_core::cycle::{Signing, UnsignedAccess};
use armgate_protocol::client::signed::{ControllerId, SigningKey};

include!(concat!(env!("OUT_DIR"), "/settings.rs"));

/// The signing settings of the build (no key: every datagram unsigned, as the seed).
pub fn signing() -> Signing {
    Signing {
        key: SIGNING_KEY.map(|bytes| SigningKey::new(&bytes).for_controller(CONTROLLER_ID)),
        unsigned: ALLOW_UNSIGNED,
    }
}
