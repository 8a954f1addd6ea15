//! The network stack and the UDP server, on the thread executor.
//!
//! * The driver is the board's ([`crate::board::NetDevice`]): the Ethernet MAC and PHY
//!   (`eth.rs`), or a Linux TAP device when the firmware runs on the host.
//! * embassy-net (smoltcp) on top: static IPv4 from `ARMGATE_IP`/`ARMGATE_GATEWAY`, or DHCP with
//!   the cargo feature `dhcp`.
//! * [`udp_server`]: receives datagrams on `ARMGATE_PORT`, drops those from sources not on the
//!   allow-list, queues the others for the control task, and sends what the control task
//!   queued (replies, notices). It never touches the core.

use core::net::IpAddr;

use embassy_futures::select::{Either, select};
use embassy_net::udp::{PacketMetadata, UdpSocket};
use embassy_net::{IpAddress, Runner, Stack, StackResources};
use static_cell::StaticCell;

use crate::link::{COUNTERS, Datagram, OUTGOING, REQUESTS, count};
use crate::settings::{ALLOW, ALLOW_LOCAL, Network, PORT};

/// The network driver: the board's Ethernet MAC and PHY, or a Linux TAP device on the host.
pub use crate::board::NetDevice as Device;

/// Datagrams the UDP socket buffers in each direction, before the queues of [`crate::link`].
pub const SOCKET_PACKETS: usize = 8;
/// Payload bytes of the UDP socket buffers in each direction (the protocol's datagrams are 31
/// bytes, 44 signed; a larger datagram that does not fit is dropped by the stack).
const SOCKET_BYTES: usize = SOCKET_PACKETS * 64;
/// Sockets of the stack: the UDP server, and the DHCP client with `dhcp`.
const SOCKETS: usize = 2;

/// The network stack's socket storage.
static RESOURCES: StaticCell<StackResources<SOCKETS>> = StaticCell::new();

/// The network stack on `device`, whose MAC address and random seed derive from the unique id
/// `uid` (the chip's, on the board).
pub fn stack(device: Device, uid: &[u8]) -> (Stack<'static>, Runner<'static, Device>) {
    embassy_net::new(
        device,
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

/// The UDP server: requests in, replies and notices out.
#[embassy_executor::task]
pub async fn udp_server(stack: Stack<'static>) {
    stack.wait_config_up().await;
    if let Some(config) = stack.config_v4() {
        defmt::info!("net: {} up, UDP port {}", config.address, PORT);
    }
    log_allow_list();
    let mut rx_meta = [PacketMetadata::EMPTY; SOCKET_PACKETS];
    let mut rx_buffer = [0; SOCKET_BYTES];
    let mut tx_meta = [PacketMetadata::EMPTY; SOCKET_PACKETS];
    let mut tx_buffer = [0; SOCKET_BYTES];
    let mut socket = UdpSocket::new(
        stack,
        &mut rx_meta,
        &mut rx_buffer,
        &mut tx_meta,
        &mut tx_buffer,
    );
    if let Err(e) = socket.bind(PORT) {
        defmt::error!("net: cannot bind UDP port {}: {}", PORT, e);
        return;
    }
    loop {
        // Both futures are cancel-safe: a datagram is taken only when its branch completes.
        match select(socket.wait_recv_ready(), OUTGOING.receive()).await {
            Either::First(()) => {
                let request = socket
                    .recv_from_with(|payload, meta| Datagram::new(payload, meta.endpoint))
                    .await;
                if !allowed(stack, request.peer.addr) {
                    count(&COUNTERS.foreign);
                } else if REQUESTS.try_send(request).is_ok() {
                    count(&COUNTERS.received);
                } else {
                    count(&COUNTERS.requests_full);
                }
            }
            Either::Second(outgoing) => {
                if socket
                    .send_to(outgoing.payload(), outgoing.peer)
                    .await
                    .is_err()
                {
                    count(&COUNTERS.send_errors);
                }
            }
        }
    }
}

/// True if `source` may command the arm: on a network of `ARMGATE_ALLOW`, or (with `local`)
/// on the board's own network. (A source address proves nothing about the sender; the
/// allow-list keeps out the rest of the network, not an attacker on it.)
fn allowed(stack: Stack<'_>, source: IpAddress) -> bool {
    let source = IpAddr::from(source);
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
