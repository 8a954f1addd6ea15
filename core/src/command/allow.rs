//! The source-address allow-list: who may command the arm. Anyone on the network could move the
//! arm otherwise. (A source address proves nothing about the sender: the list keeps out the rest
//! of the network, not an attacker on it.) `armgate-sim` and the firmware both check with it.

use core::fmt;
use core::net::IpAddr;
use core::str::FromStr;

/// One network, e.g. `127.0.0.0/8`, `192.168.1.20` (one host) or `::1/128`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Network {
    addr: IpAddr,
    prefix: u8,
}

impl Network {
    /// The network of `addr` with `prefix` leading bits (more bits than the address has count
    /// as all of them).
    pub const fn new(addr: IpAddr, prefix: u8) -> Self {
        let bits = address_bits(addr);
        Self {
            addr,
            prefix: if prefix > bits { bits } else { prefix },
        }
    }

    /// The network's address, as given.
    pub const fn addr(&self) -> IpAddr {
        self.addr
    }

    /// The prefix length.
    pub const fn prefix(&self) -> u8 {
        self.prefix
    }

    /// True if `ip` lies in this network (an IPv4 address never lies in an IPv6 network, nor
    /// the reverse). An IPv4-mapped IPv6 address (`::ffff:a.b.c.d`, what a socket bound to
    /// `[::]` reports for an IPv4 sender) is the IPv4 address it maps.
    pub fn contains(&self, ip: IpAddr) -> bool {
        let (net, ip) = match (self.addr, ip.to_canonical()) {
            (IpAddr::V4(net), IpAddr::V4(ip)) => (u32::from(net).into(), u32::from(ip).into()),
            (IpAddr::V6(net), IpAddr::V6(ip)) => (u128::from(net), u128::from(ip)),
            _ => return false,
        };
        let shift = u32::from(address_bits(self.addr) - self.prefix);
        net.checked_shr(shift).unwrap_or(0) == ip.checked_shr(shift).unwrap_or(0)
    }
}

/// 32 for IPv4, 128 for IPv6.
const fn address_bits(addr: IpAddr) -> u8 {
    if addr.is_ipv4() { 32 } else { 128 }
}

/// Why a text is not a network.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NetworkError {
    /// The part before `/` is not an IPv4 or IPv6 address.
    BadAddress,
    /// The prefix length is not a number from 0 to `max` (32 for IPv4, 128 for IPv6).
    BadPrefix {
        /// The longest prefix for the address.
        max: u8,
    },
}

impl fmt::Display for NetworkError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::BadAddress => f.write_str("not an IP address or network"),
            Self::BadPrefix { max } => write!(f, "prefix must be 0..={max}"),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for NetworkError {}

impl FromStr for Network {
    type Err = NetworkError;

    /// `address/prefix`, or a bare address for one host; spaces around the parts are ignored.
    fn from_str(s: &str) -> Result<Self, NetworkError> {
        let (addr, prefix) = match s.split_once('/') {
            Some((a, p)) => (a, Some(p)),
            None => (s, None),
        };
        let addr: IpAddr = addr.trim().parse().map_err(|_| NetworkError::BadAddress)?;
        let max = address_bits(addr);
        let prefix = match prefix {
            Some(p) => p
                .trim()
                .parse::<u8>()
                .ok()
                .filter(|p| *p <= max)
                .ok_or(NetworkError::BadPrefix { max })?,
            None => max,
        };
        Ok(Self { addr, prefix })
    }
}

impl fmt::Display for Network {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.addr, self.prefix)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::net::Ipv4Addr;

    #[test]
    fn networks_match_their_members_only() {
        let lo: Network = "127.0.0.0/8".parse().unwrap();
        assert!(lo.contains("127.1.2.3".parse().unwrap()));
        assert!(!lo.contains("128.0.0.1".parse().unwrap()));
        assert!(!lo.contains("::1".parse().unwrap()));
        let host: Network = "192.168.1.20".parse().unwrap();
        assert!(host.contains("192.168.1.20".parse().unwrap()));
        assert!(!host.contains("192.168.1.21".parse().unwrap()));
        let all: Network = "0.0.0.0/0".parse().unwrap();
        assert!(all.contains("8.8.8.8".parse().unwrap()));
        let v6: Network = "::1/128".parse().unwrap();
        assert!(v6.contains("::1".parse().unwrap()));
        // An IPv4 sender seen through a dual-stack socket.
        assert!(lo.contains("::ffff:127.0.0.1".parse().unwrap()));
        assert!(!lo.contains("::ffff:128.0.0.1".parse().unwrap()));
        assert_eq!(
            "10.0.0.0/33".parse::<Network>(),
            Err(NetworkError::BadPrefix { max: 32 })
        );
        assert_eq!("nonsense".parse::<Network>(), Err(NetworkError::BadAddress));
    }

    #[test]
    fn new_clamps_the_prefix_and_display_round_trips() {
        let net = Network::new(IpAddr::V4(Ipv4Addr::new(192, 168, 1, 0)), 40);
        assert_eq!(net.prefix(), 32);
        let net: Network = " 192.168.1.0 / 24 ".parse().unwrap();
        assert_eq!(net.to_string(), "192.168.1.0/24");
        assert_eq!(net.to_string().parse::<Network>(), Ok(net));
        assert!(net.contains(IpAddr::V4(Ipv4Addr::new(192, 168, 1, 255))));
        assert!(!net.contains(IpAddr::V4(Ipv4Addr::new(192, 168, 2, 1))));
    }
}
