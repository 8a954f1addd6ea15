//! Network settings embedded at build time.
//!
//! `build.rs` reads `ARMGATE_IP`, `ARMGATE_GATEWAY`, `ARMGATE_PORT` and `ARMGATE_ALLOW` and
//! writes the constants below (`OUT_DIR/settings.rs`); a malformed value fails the build.
//! Defaults: `192.168.1.50/24`, no gateway, port 7031, allow-list `local` (the board's own
//! network). See `docs/firmware.md`.

use core::net::Ipv4Addr;

/// An IPv4 network: an address and a prefix length (0..=32).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Network {
    address: Ipv4Addr,
    prefix_len: u8,
}

impl Network {
    /// The network of `address` with `prefix_len` leading bits (more than 32 count as 32).
    pub const fn new(address: Ipv4Addr, prefix_len: u8) -> Self {
        Self {
            address,
            prefix_len: if prefix_len > 32 { 32 } else { prefix_len },
        }
    }

    /// True if `address` lies in this network.
    pub fn contains(&self, address: Ipv4Addr) -> bool {
        let mask = u32::MAX
            .checked_shl(32 - u32::from(self.prefix_len))
            .unwrap_or(0);
        (u32::from(address) ^ u32::from(self.address)) & mask == 0
    }
}

impl defmt::Format for Network {
    fn format(&self, f: defmt::Formatter<'_>) {
        let [a, b, c, d] = self.address.octets();
        defmt::write!(f, "{}.{}.{}.{}/{}", a, b, c, d, self.prefix_len);
    }
}

include!(concat!(env!("OUT_DIR"), "/settings.rs"));
