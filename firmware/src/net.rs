//! Ethernet and the UDP server, on the thread executor.
//!
//! * The STM32H743's Ethernet MAC in RMII mode with the NUCLEO-H743ZI2's LAN8742A PHY at SMI
//!   address 0: REF_CLK PA1, MDIO PA2, MDC PC1, CRS_DV PA7, RXD0 PC4, RXD1 PC5, TX_EN PG11,
//!   TXD0 PG13, TXD1 PB13.
//! * embassy-net (smoltcp) on top: static IPv4 from `ARMGATE_IP`/`ARMGATE_GATEWAY`, or DHCP with
//!   the cargo feature `dhcp`.
//! * [`udp_server`]: receives datagrams on `ARMGATE_PORT`, drops those from sources not on the
//!   allow-list, queues the others for the control task, and sends what the control task
//!   queued (replies, notices). It never touches the core.
//!
//! The DMA descriptors and packet buffers ([`PacketQueue`]) are a `static`, so they lie in the
//! RAM region of `memory.x`: the AXI SRAM at 0x2400_0000, which the Ethernet DMA can reach (the
//! DTCM at 0x2000_0000 would not be). The D-cache is off, so no cache maintenance is needed.

use core::net::IpAddr;

use embassy_futures::select::{Either, select};
use embassy_net::udp::{PacketMetadata, UdpSocket};
use embassy_net::{IpAddress, Runner, Stack, StackResources};
use embassy_stm32::eth::{self, Ethernet, GenericPhy, PacketQueue, Sma};
use embassy_stm32::peripherals::{ETH, ETH_SMA, PA1, PA2, PA7, PB13, PC1, PC4, PC5, PG11, PG13};
use embassy_stm32::{Peri, bind_interrupts};
use static_cell::StaticCell;

use crate::link::{COUNTERS, Datagram, OUTGOING, REQUESTS, count};
use crate::settings::{ALLOW, ALLOW_LOCAL, Network, PORT};

bind_interrupts!(struct Irqs {
    ETH => eth::InterruptHandler;
});

/// The Ethernet driver of this board.
pub type Device = Ethernet<'static, ETH, GenericPhy<Sma<'static, ETH_SMA>>>;

/// SMI address of the NUCLEO-H743ZI2's LAN8742A.
const PHY_ADDRESS: u8 = 0;
/// DMA descriptors (and 1.5 KiB buffers) per direction: a few frames of slack while the thread
/// executor is busy; client traffic is one 31-byte datagram per request.
const DMA_FRAMES: usize = 4;
/// Datagrams the UDP socket buffers in each direction, before the queues of [`crate::link`].
pub const SOCKET_PACKETS: usize = 8;
/// Payload bytes of the UDP socket buffers in each direction (the protocol's datagrams are 31
/// bytes; a larger datagram that does not fit is dropped by the stack).
const SOCKET_BYTES: usize = SOCKET_PACKETS * 64;
/// Sockets of the stack: the UDP server, and the DHCP client with `dhcp`.
const SOCKETS: usize = 2;

/// The Ethernet DMA's descriptors and packet buffers.
static PACKETS: StaticCell<PacketQueue<DMA_FRAMES, DMA_FRAMES>> = StaticCell::new();
/// The network stack's socket storage.
static RESOURCES: StaticCell<StackResources<SOCKETS>> = StaticCell::new();

/// The Ethernet pins and peripherals of the NUCLEO-H743ZI2 (RMII).
pub struct Pins {
    /// The Ethernet MAC.
    pub eth: Peri<'static, ETH>,
    /// Its station management (MDIO/MDC) interface.
    pub sma: Peri<'static, ETH_SMA>,
    /// RMII REF_CLK (50 MHz from the PHY).
    pub ref_clk: Peri<'static, PA1>,
    /// MDIO.
    pub mdio: Peri<'static, PA2>,
    /// MDC.
    pub mdc: Peri<'static, PC1>,
    /// RMII CRS_DV.
    pub crs_dv: Peri<'static, PA7>,
    /// RMII RXD0.
    pub rxd0: Peri<'static, PC4>,
    /// RMII RXD1.
    pub rxd1: Peri<'static, PC5>,
    /// RMII TX_EN.
    pub tx_en: Peri<'static, PG11>,
    /// RMII TXD0.
    pub txd0: Peri<'static, PG13>,
    /// RMII TXD1.
    pub txd1: Peri<'static, PB13>,
}

/// Starts the Ethernet MAC and PHY and creates the network stack. `uid` is the chip's unique
/// id: the MAC address (locally administered) and the stack's random seed derive from it.
pub fn init(pins: Pins, uid: &[u8; 12]) -> (Stack<'static>, Runner<'static, Device>) {
    let hash = fnv1a(uid);
    let [_, _, _, a, b, c, d, e] = hash.to_be_bytes();
    // Locally administered (bit 1), unicast (bit 0 clear).
    let mac = [0x02, a, b, c, d, e];
    defmt::info!(
        "net: MAC {=[u8]:02x}, PHY at SMI address {}",
        mac,
        PHY_ADDRESS
    );
    let phy = GenericPhy::new(Sma::new(pins.sma, pins.mdio, pins.mdc), PHY_ADDRESS);
    let device = Ethernet::new_with_phy(
        PACKETS.init(PacketQueue::new()),
        pins.eth,
        Irqs,
        pins.ref_clk,
        pins.crs_dv,
        pins.rxd0,
        pins.rxd1,
        pins.txd0,
        pins.txd1,
        pins.tx_en,
        mac,
        phy,
    );
    embassy_net::new(
        device,
        ip_config(),
        RESOURCES.init(StackResources::new()),
        hash,
    )
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
