//! Start-up: clocks, the embedded robot, the watchdog, Ethernet, the executors and their tasks.

use armgate_core::config::ValidRobot;
use armgate_core::cycle::{FlashLog, FlashSectors, RECORD_LEN};
use embassy_executor::{Executor, InterruptExecutor};
use embassy_stm32::flash::{Blocking, Flash};
use embassy_stm32::interrupt;
use embassy_stm32::interrupt::{InterruptExt, Priority};
use embassy_stm32::wdg::IndependentWatchdog;
use static_cell::StaticCell;
use {defmt_rtt as _, panic_probe as _};

use crate::{clocks, config, control, drives, eth, net, settings, telemetry};

/// The network driver of this board.
pub type NetDevice = eth::Device;
/// Where the replay reservation is kept across restarts: a log in the last two sectors of
/// flash bank 2 (`memory.x` leaves them out of the image).
pub type ReplayStore = FlashLog<ReplaySectors>;

/// The flash sectors of the replay log: the last two of bank 2 (offsets from the flash's
/// start), 128 KiB each.
const REPLAY_SECTORS: [u32; 2] = [0x1C_0000, 0x1E_0000];
/// Bytes per sector.
const SECTOR_LEN: u32 = 128 * 1024;

/// The replay log's two sectors through embassy's blocking flash driver. A record is programmed
/// in one flash word (from the control task, at most once per 2 s of signed use); sectors are
/// erased only at start.
pub struct ReplaySectors(Flash<'static, Blocking>);

impl ReplaySectors {
    /// The offset of `record` in `sector`, if both exist.
    fn offset(sector: u8, record: u32) -> Option<u32> {
        let start = REPLAY_SECTORS.get(usize::from(sector))?;
        let at = record.checked_mul(RECORD_LEN as u32)?;
        (at < SECTOR_LEN).then(|| start.saturating_add(at))
    }
}

impl FlashSectors for ReplaySectors {
    fn records(&self) -> u32 {
        SECTOR_LEN / RECORD_LEN as u32
    }

    fn read(&mut self, sector: u8, record: u32) -> Option<[u8; RECORD_LEN]> {
        let mut bytes = [0; RECORD_LEN];
        let offset = Self::offset(sector, record)?;
        self.0.blocking_read(offset, &mut bytes).ok()?;
        Some(bytes)
    }

    fn write(&mut self, sector: u8, record: u32, bytes: &[u8; RECORD_LEN]) -> bool {
        Self::offset(sector, record).is_some_and(|at| self.0.blocking_write(at, bytes).is_ok())
    }

    fn erase(&mut self, sector: u8) -> bool {
        REPLAY_SECTORS
            .get(usize::from(sector))
            .is_some_and(|start| {
                let end = start.saturating_add(SECTOR_LEN);
                self.0.blocking_erase(*start, end).is_ok()
            })
    }
}
/// The watchdog the control task feeds.
pub type Watchdog = IndependentWatchdog<'static, embassy_stm32::peripherals::IWDG1>;

/// Priority of the control executor's interrupt. The control task preempts the thread executor
/// (networking, status); the FDCAN interrupt (P5, `can.rs`) and the short hardware handlers,
/// which embassy leaves at P0 (time driver, Ethernet, DMA), preempt the control task.
const CONTROL_PRIORITY: Priority = Priority::P6;

/// The control executor; its interrupt vector is `UART4`, a peripheral this board does not use.
static CONTROL_EXECUTOR: InterruptExecutor = InterruptExecutor::new();
/// The thread-mode executor: network stack, UDP server, status line.
static THREAD_EXECUTOR: StaticCell<Executor> = StaticCell::new();
/// The robot description, decoded once at boot and shared by every task.
static ROBOT: StaticCell<ValidRobot> = StaticCell::new();

/// The control executor's interrupt: polls its tasks when one of them is woken.
// `unsafe` is required: `on_interrupt` must only be called from the executor's own interrupt
// handler, which this is.
#[allow(unsafe_code)]
#[interrupt]
unsafe fn UART4() {
    // SAFETY: this is the interrupt `CONTROL_EXECUTOR` was started on, and it is unmasked only
    // by `start`, so the executor is initialised.
    unsafe { CONTROL_EXECUTOR.on_interrupt() }
}

#[cortex_m_rt::entry]
fn main() -> ! {
    if let Some(mut core) = cortex_m::Peripherals::take() {
        // The I-cache is safe to enable at any time. The D-cache stays off: the Ethernet DMA
        // descriptors and buffers would need a non-cacheable MPU region (docs/firmware.md).
        core.SCB.enable_icache();
    }
    let p = embassy_stm32::init(clocks::config());
    defmt::info!(
        "armgate firmware {}: 480 MHz, embedded robot {} bytes",
        env!("CARGO_PKG_VERSION"),
        config::embedded_len()
    );
    // The watchdog stops while a debugger halts the core (breakpoints would reset the board).
    embassy_stm32::pac::DBGMCU
        .apb4fzr1()
        .modify(|w| w.set_iwdg1(true));

    let robot: &'static ValidRobot = match config::load() {
        Ok(robot) => ROBOT.init(robot),
        // Unrecoverable: build.rs validated this very description, so only a core change since
        // the build can get here. Halt with the reason rather than run an unknown arm (the
        // watchdog is not running yet: the board stays halted).
        Err(e) => defmt::panic!("{}", e),
    };

    // The replay log before the watchdog: opening it may erase a flash sector (seconds).
    let store = FlashLog::open(ReplaySectors(Flash::new_blocking(p.FLASH)));

    // The control task first: from here on the watchdog runs and only the control task feeds
    // it; the control task preempts everything below.
    let drives = drives::new(robot, drives::bus::open(robot, p.FDCAN1, p.PD0, p.PD1));
    defmt::info!("drives: {}", drives::describe());
    let timeout = control::watchdog_timeout(control::period(robot));
    let timeout_us = u32::try_from(timeout.as_micros()).unwrap_or(u32::MAX);
    let watchdog = IndependentWatchdog::new(p.IWDG1, timeout_us);
    interrupt::UART4.set_priority(CONTROL_PRIORITY);
    let control_spawner = CONTROL_EXECUTOR.start(interrupt::UART4);
    let signing = (settings::signing(), store);
    match control::run(robot, drives, watchdog, signing) {
        Ok(task) => control_spawner.spawn(task),
        Err(e) => defmt::panic!("cannot spawn the control task: {}", e),
    }

    let uid = embassy_stm32::uid::uid();
    let device = eth::init(
        eth::Pins {
            eth: p.ETH,
            sma: p.ETH_SMA,
            ref_clk: p.PA1,
            mdio: p.PA2,
            mdc: p.PC1,
            crs_dv: p.PA7,
            rxd0: p.PC4,
            rxd1: p.PC5,
            tx_en: p.PG11,
            txd0: p.PG13,
            txd1: p.PB13,
        },
        net::mac_address(&uid),
    );
    let (stack, runner) = net::stack(device, &uid);

    let executor = THREAD_EXECUTOR.init(Executor::new());
    executor.run(|spawner| {
        match net::runner(runner) {
            Ok(task) => spawner.spawn(task),
            Err(e) => defmt::panic!("cannot spawn the network stack: {}", e),
        }
        match net::udp_server(stack) {
            Ok(task) => spawner.spawn(task),
            Err(e) => defmt::panic!("cannot spawn the UDP server: {}", e),
        }
        match telemetry::run(stack) {
            Ok(task) => spawner.spawn(task),
            Err(e) => defmt::panic!("cannot spawn the status task: {}", e),
        }
    })
}
