//! Start-up: clocks, the embedded robot, the executors and their tasks.

use armgate_core::config::RobotConfig;
use armgate_core::kinematics::Chain;
use embassy_executor::{Executor, InterruptExecutor};
use embassy_stm32::interrupt;
use embassy_stm32::interrupt::{InterruptExt, Priority};
use static_cell::StaticCell;
use {defmt_rtt as _, panic_probe as _};

use crate::{clocks, config, control};

/// Priority of the control executor's interrupt. The control tasks preempt the thread executor
/// (networking, drives); the short hardware handlers, which embassy leaves at P0 (time driver,
/// DMA, peripheral interrupts), preempt the control tasks. P1..P5 stay free for anything that
/// must preempt control later.
const CONTROL_PRIORITY: Priority = Priority::P6;

/// The control executor; its interrupt vector is `UART4`, a peripheral this board does not use.
static CONTROL_EXECUTOR: InterruptExecutor = InterruptExecutor::new();
/// The thread-mode executor (networking, drives, watchdog: later).
static THREAD_EXECUTOR: StaticCell<Executor> = StaticCell::new();
/// The robot description, decoded once at boot and shared by every task.
static ROBOT: StaticCell<RobotConfig> = StaticCell::new();

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
        // The I-cache is safe to enable at any time. The D-cache is left off until the
        // Ethernet DMA buffers get a non-cacheable MPU region (networking issue).
        core.SCB.enable_icache();
    }
    let _peripherals = embassy_stm32::init(clocks::config());
    defmt::info!(
        "armgate firmware {}: 480 MHz, embedded robot {} bytes",
        env!("CARGO_PKG_VERSION"),
        config::embedded_len()
    );

    let robot: &'static RobotConfig = match config::load() {
        Ok(robot) => ROBOT.init(robot),
        // Unrecoverable: build.rs validated this very description, so only a core change since
        // the build can get here. Halt with the reason rather than run an unknown arm.
        Err(e) => defmt::panic!("{}", e),
    };
    let chain = Chain::new(robot);

    interrupt::UART4.set_priority(CONTROL_PRIORITY);
    let control_spawner = CONTROL_EXECUTOR.start(interrupt::UART4);
    match control::run(robot, chain) {
        Ok(task) => control_spawner.spawn(task),
        Err(e) => defmt::panic!("cannot spawn the control task: {}", e),
    }

    let executor = THREAD_EXECUTOR.init(Executor::new());
    executor.run(|_spawner| {
        // Thread-mode tasks (UDP, CAN, watchdog) are spawned here by later issues.
    })
}
