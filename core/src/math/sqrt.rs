//! The square root the core takes everywhere: on the Cortex-M7 the FPU's own `vsqrt.f64` (one
//! instruction, about 14 cycles), not `libm::sqrt` (a software square root of about 95
//! instructions: libm has no ARM implementation). Elsewhere (the host) `libm::sqrt`. Both are
//! correctly rounded (IEEE 754), so the results are the same bits.
//!
//! The hard-float Arm build requires a double-precision FPU: `.cargo/config.toml` builds for
//! `target-cpu=cortex-m7` (the STM32H743's FPv5-D16); without it every `f64` operation would
//! be a soft-float call anyway.

/// `√x`; NaN for a negative `x`.
#[inline(always)]
pub fn sqrt(x: f64) -> f64 {
    #[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
    {
        let root: f64;
        // SAFETY: one FPU instruction on registers: no memory, stack or flags touched.
        #[allow(unsafe_code)]
        unsafe {
            core::arch::asm!(
                "vsqrt.f64 {root}, {x}",
                root = lateout(dreg_low16) root,
                x = in(dreg_low16) x,
                options(pure, nomem, nostack, preserves_flags),
            );
        }
        root
    }
    #[cfg(not(all(target_arch = "arm", target_abi = "eabihf")))]
    {
        libm::sqrt(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn is_libm_sqrt() {
        for x in [0.0, 1e-300, 0.5, 2.0, 1e300, f64::INFINITY] {
            assert_eq!(sqrt(x).to_bits(), libm::sqrt(x).to_bits());
        }
        assert!(sqrt(-1.0).is_nan());
    }
}
