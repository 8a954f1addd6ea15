//! The network stack and the UDP server, on the thread executor.
//!
//! * The driver is the board's ([`crate::board::NetDevice`]): the Ethernet MAC and PHY
//!   (`eth.rs`), or a Linux TAP device when the firmware runs on the host.
//! * embassy-net (smoltcp) on top: static IPv4 from `ARMGATE_IP`/`ARMGATE_GATEWAY`, or DHCP with
//!   the cargo feature `dhcp`.
//! * [`udp_server`]: receives datagrams on `ARMGATE_PORT`, drops those from sources not on the
//!   allow-list, queues the others for the control task ([`crate::link::offer`], a bounded
//!   share per source), and, in a loop of its own on a socket of its own, sends what the control
//!   task queued (replies, notices; [`crate::sender`]). Receiving never waits on a send. It
//!   never touches the core.

use core::net::IpAddr;

use embassy_futures::join::join;
use embassy_net::udp::{PacketMetadata, UdpSocket};
use embassy_net::{Runner, Stack, StackResources};
use static_cell::StaticCell;

use crate::ingress::{FRAMES_PER_POLL, Paced};
use crate::link::{COUNTERS, Datagram, StackDrops, count, offer};
use crate::sender;
use crate::settings::{ALLOW, ALLOW_LOCAL, Network, PORT};

/// The network driver: the board's Ethernet MAC and PHY, or a Linux TAP device on the host,
/// paced ([`crate::ingress`]).
pub type Device = Paced<crate::board::NetDevice>;

/// Datagrams the receiving socket buffers before the queues of [`crate::link`]: two paced
/// batches of frames, so that it never overflows between two runs of the server.
pub const SOCKET_PACKETS: usize = 2 * FRAMES_PER_POLL;
/// Payload bytes per buffered datagram (the protocol's datagrams are 31 bytes, 44 signed; a
/// larger datagram that does not fit is dropped by the stack).
pub const PACKET_BYTES: usize = 64;
/// Sockets of the stack: the UDP server's three (receiving; sending to known destinations and
/// to the others, [`sender`]), and the DHCP client with `dhcp`.
const SOCKETS: usize = 4;

/// The network stack's socket storage.
static RESOURCES: StaticCell<StackResources<SOCKETS>> = StaticCell::new();

/// The network stack on `device`, whose MAC address and random seed derive from the unique id
/// `uid` (the chip's, on the board).
pub fn stack(
    device: crate::board::NetDevice,
    uid: &[u8],
) -> (Stack<'static>, Runner<'static, Device>) {
    embassy_net::new(
        Paced::new(device),
        ip_config(),
        RESOURCES.init(StackResources::new()),
        fnv1a(uid),
    )
}

/// A locally administered unicast MAC address derived from the unique id `uid`.
pub fn mac_address(uid: &[u8]) -> [u8; 6] {
    let [_, _, _, a, b, c, d, e] = fnv1a(uid).to_be_bytes();
    // Locally administered (bit 1), unicast (bit 0 clear).
    [0x02, a, b, c, d, e]
}

/// Static IPv4 from `ARMGATE_IP` and `ARMGATE_GATEWAY`.
#[cfg(not(feature = "dhcp"))]
fn ip_config() -> embassy_net::Config {
    use crate::settings::{ADDRESS, GATEWAY, PREFIX_LEN};
    embassy_net::Config::ipv4_static(embassy_net::StaticConfigV4 {
        address: embassy_net::Ipv4Cidr::new(ADDRESS, PREFIX_LEN),
        gateway: GATEWAY,
        dns_servers: Default::default(),
    })
}

/// IPv4 from a DHCP server.
#[cfg(feature = "dhcp")]
fn ip_config() -> embassy_net::Config {
    embassy_net::Config::dhcpv4(Default::default())
}

/// The network stack's task: moves frames between the driver and the sockets.
#[embassy_executor::task]
pub async fn runner(mut runner: Runner<'static, Device>) -> ! {
    runner.run().await
}

/// The UDP server: requests in, replies and notices out, in two loops that never wait on each
/// other.
#[embassy_executor::task]
pub async fn udp_server(stack: Stack<'static>) {
    stack.wait_config_up().await;
    if let Some(config) = stack.config_v4() {
        defmt::info!("net: {} up, UDP port {}", config.address, PORT);
    }
    log_allow_list();
    let mut rx_meta = [PacketMetadata::EMPTY; SOCKET_PACKETS];
    let mut rx_buffer = [0; SOCKET_PACKETS * PACKET_BYTES];
    // Made first: smoltcp gives a datagram to the first socket bound to its port.
    let mut receiving = UdpSocket::new(stack, &mut rx_meta, &mut rx_buffer, &mut [], &mut []);
    if let Err(e) = receiving.bind(PORT) {
        defmt::error!("net: cannot bind UDP port {}: {}", PORT, e);
        return;
    }
    let (mut known, mut probing) = (sender::Buffers::new(), sender::Buffers::new());
    join(
        receive(stack, &mut receiving),
        sender::run(stack, &mut known, &mut probing),
    )
    .await;
}

/// Takes the datagrams the stack received, for ever: those from allowed sources are offered to
/// the control task, the others counted, and what the stack dropped before them too.
async fn receive(stack: Stack<'static>, socket: &mut UdpSocket<'_>) {
    let mut drops = StackDrops::default();
    loop {
        let request = socket
            .recv_from_with(|payload, meta| Datagram::new(payload, meta.endpoint.into()))
            .await;
        drops.taken(!socket.may_recv());
        if !allowed(stack, request.peer.ip()) {
            count(&COUNTERS.foreign);
        } else if offer(request) {
            count(&COUNTERS.received);
        } else {
            count(&COUNTERS.requests_full);
        }
    }
}

/// True if `source` may command the arm: on a network of `ARMGATE_ALLOW`, or (with `local`)
/// on the board's own network. (A source address proves nothing about the sender; the
/// allow-list keeps out the rest of the network, not an attacker on it.)
fn allowed(stack: Stack<'_>, source: IpAddr) -> bool {
    ALLOW.iter().any(|network| network.contains(source))
        || (ALLOW_LOCAL
            && stack.config_v4().is_some_and(|config| {
                let local = IpAddr::V4(config.address.address());
                Network::new(local, config.address.prefix_len()).contains(source)
            }))
}

fn log_allow_list() {
    if ALLOW_LOCAL {
        defmt::info!("net: allowing the local network");
    }
    for network in ALLOW {
        defmt::info!("net: allowing {}", defmt::Display2Format(network));
    }
}

/// FNV-1a, 64 bits.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3)
    })
}
