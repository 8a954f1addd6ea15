//! The NUCLEO-H743ZI2's Ethernet: the STM32H743's MAC in RMII mode with the LAN8742A PHY at SMI
//! address 0: REF_CLK PA1, MDIO PA2, MDC PC1, CRS_DV PA7, RXD0 PC4, RXD1 PC5, TX_EN PG11, TXD0
//! PG13, TXD1 PB13.
//!
//! The DMA descriptors and packet buffers ([`PacketQueue`]) are a `static`, so they lie in the
//! RAM region of `memory.x`: the AXI SRAM at 0x2400_0000, which the Ethernet DMA can reach (the
//! DTCM at 0x2000_0000 would not be). The D-cache is off, so no cache maintenance is needed.

use embassy_stm32::eth::{self, Ethernet, GenericPhy, PacketQueue, Sma};
use embassy_stm32::peripherals::{ETH, ETH_SMA, PA1, PA2, PA7, PB13, PC1, PC4, PC5, PG11, PG13};
use embassy_stm32::{Peri, bind_interrupts};
use static_cell::StaticCell;

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

/// The Ethernet DMA's descriptors and packet buffers.
static PACKETS: StaticCell<PacketQueue<DMA_FRAMES, DMA_FRAMES>> = StaticCell::new();

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

/// Starts the Ethernet MAC and PHY, with the MAC address `mac`.
pub fn init(pins: Pins, mac: [u8; 6]) -> Device {
    defmt::info!(
        "net: MAC {=[u8]:02x}, PHY at SMI address {}",
        mac,
        PHY_ADDRESS
    );
    let phy = GenericPhy::new(Sma::new(pins.sma, pins.mdio, pins.mdc), PHY_ADDRESS);
    Ethernet::new_with_phy(
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
    )
}
