//! Start-up, panic and fault handlers, shared by every benchmark binary: everything reports over
//! semihosting and exits QEMU.

use cortex_m_rt::{ExceptionFrame, exception};
use cortex_m_semihosting::{debug, hprintln};

use crate::counter::Counter;

/// Starts and calibrates the counter, runs `bench` and exits QEMU with its verdict.
pub fn run(bench: impl FnOnce(&Counter) -> bool) -> ! {
    let ok = match cortex_m::Peripherals::take() {
        Some(core) => bench(&Counter::start(core.SYST)),
        None => false,
    };
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    halt()
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo<'_>) -> ! {
    hprintln!("panic: {}", info);
    debug::exit(debug::EXIT_FAILURE);
    halt()
}

// `unsafe` is required by cortex-m-rt for a HardFault handler (it runs on any stack state).
#[allow(unsafe_code)]
#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    hprintln!("hard fault at pc {:#010x}", frame.pc());
    debug::exit(debug::EXIT_FAILURE);
    halt()
}

/// Waits forever (only reached if the debugger resumes after an exit request).
fn halt() -> ! {
    loop {
        cortex_m::asm::wfi();
    }
}
