//! Entry point, panic and fault handlers: everything reports over semihosting and exits QEMU.

use cortex_m_rt::{ExceptionFrame, entry, exception};
use cortex_m_semihosting::{debug, hprintln};

use crate::{bench, counter::Counter};

#[entry]
fn main() -> ! {
    let ok = match cortex_m::Peripherals::take() {
        Some(core) => bench::run(Counter::start(core.SYST)),
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
