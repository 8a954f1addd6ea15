//! Network settings embedded at build time.
//!
//! `build.rs` reads `ARMGATE_IP`, `ARMGATE_GATEWAY`, `ARMGATE_PORT` and `ARMGATE_ALLOW` and
//! writes the constants below (`OUT_DIR/settings.rs`); a malformed value fails the build.
//! Defaults: `192.168.1.50/24`, no gateway, port 7031, allow-list `local` (the board's own
//! network). See `docs/firmware.md`.

use core::net::Ipv4Addr;

pub use armgate_core::command::Network;

include!(concat!(env!("OUT_DIR"), "/settings.rs"));
