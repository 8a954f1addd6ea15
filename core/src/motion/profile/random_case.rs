//! The random profiles of the tests and the benchmarks: one distribution, so that the
//! randomised test, the host benchmark (`core/examples/profile_bench.rs`) and the Cortex-M7
//! benchmark (`qemu-bench`) cover the same inputs draw for draw.

use super::{DoubleS, JerkLimits};
use crate::rng::SplitMix64;

/// One planning request: `DoubleS::new(distance, limits, min_duration)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RandomCase {
    /// Either sign, 1e-6 to 1e2 (log-uniform).
    pub distance: f64,
    /// Velocity 1e-3..1e2, acceleration 1e-3..1e3, jerk 1e-2..1e5 (each log-uniform): every
    /// combination of reached and unreached limits occurs.
    pub limits: JerkLimits,
    /// Half the cases 0 (minimum time); the other half `1 + x` times the minimum time with
    /// `x` log-uniform in 1e-9..1e3 (barely to a thousand times longer), which stretches the
    /// profile as time synchronisation does.
    pub min_duration: f64,
}

impl RandomCase {
    /// The next case from `rng`.
    pub fn draw(rng: &mut SplitMix64) -> Self {
        let limits = JerkLimits::new(
            rng.log_uniform(1e-3, 1e2),
            rng.log_uniform(1e-3, 1e3),
            rng.log_uniform(1e-2, 1e5),
        );
        let sign = if rng.next_f64() < 0.5 { -1.0 } else { 1.0 };
        let distance = sign * rng.log_uniform(1e-6, 1e2);
        let stretch = rng.next_f64();
        let min_duration = if stretch < 0.5 {
            0.0
        } else {
            let fastest = DoubleS::new(distance, limits, 0.0).map_or(0.0, |p| p.duration());
            fastest * (1.0 + rng.log_uniform(1e-9, 1e3))
        };
        Self {
            distance,
            limits,
            min_duration,
        }
    }

    /// The profile this case asks for.
    pub fn plan(&self) -> Result<DoubleS, super::ProfileError> {
        DoubleS::new(self.distance, self.limits, self.min_duration)
    }
}
