//! Clock tree of the NUCLEO-H743ZI2: 480 MHz core clock from the ST-LINK's 8 MHz.

use embassy_stm32::rcc::{
    AHBPrescaler, APBPrescaler, Hse, HseMode, Pll, PllDiv, PllMul, PllPreDiv, PllSource, Sysclk,
    VoltageScale, mux,
};
use embassy_stm32::time::Hertz;

/// The embassy configuration for 480 MHz.
///
/// * HSE: 8 MHz from the ST-LINK's MCO, bypass mode (no crystal on the NUCLEO by default).
/// * PLL1: 8 MHz / 1 × 120 = 960 MHz VCO (wide range); P / 2 = 480 MHz system clock,
///   Q / 8 = 120 MHz: FDCAN's kernel clock (every bit rate of the robot files, 125 k to
///   1 Mbit/s, divides it exactly).
/// * D1CPRE / 1 = 480 MHz CPU, HPRE / 2 = 240 MHz AXI/AHB, every APB / 2 = 120 MHz.
/// * VOS0 (voltage scale 0, overdrive, which embassy enables through VOS1): required above
///   400 MHz; the H743's LDO supply is fixed (no SMPS), which embassy sets up by default.
///   Revision V silicon only (the NUCLEO-H743ZI2 carries it); revision Y stops at 400 MHz.
pub fn config() -> embassy_stm32::Config {
    let mut config = embassy_stm32::Config::default();
    let rcc = &mut config.rcc;
    rcc.hse = Some(Hse {
        freq: Hertz::mhz(8),
        mode: HseMode::Bypass,
    });
    rcc.pll1 = Some(Pll {
        source: PllSource::HSE,
        prediv: PllPreDiv::DIV1,
        mul: PllMul::MUL120,
        fracn: None,
        divp: Some(PllDiv::DIV2),
        divq: Some(PllDiv::DIV8),
        divr: None,
    });
    rcc.sys = Sysclk::PLL1_P;
    rcc.d1c_pre = AHBPrescaler::DIV1;
    rcc.ahb_pre = AHBPrescaler::DIV2;
    rcc.apb1_pre = APBPrescaler::DIV2;
    rcc.apb2_pre = APBPrescaler::DIV2;
    rcc.apb3_pre = APBPrescaler::DIV2;
    rcc.apb4_pre = APBPrescaler::DIV2;
    rcc.voltage_scale = VoltageScale::Scale0;
    rcc.mux.fdcansel = mux::Fdcansel::PLL1_Q;
    config
}
