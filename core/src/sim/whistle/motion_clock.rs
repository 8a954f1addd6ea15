//! The simulated drive's motion clock, and its lock to the controller's clock by SYNC and Time
//! Stamp pairs.
//!
//! Documented (Elmo MAN-CAN301IG ch. 8 "SYNC and Time Stamp"): the drive's motion clock counts
//! microseconds; the drive latches it when a SYNC arrives; a Time Stamp carries the master's
//! clock at that SYNC, and the drive adjusts its clock by the difference, filtered so that the
//! stamping jitter does not disturb the motion, "about 200 SYNC-Time Stamp pairs" to full
//! precision. Then "multiple servo drives can perform complex synchronized motion with exact
//! timing set by the network master" (and MAN-CAN402IG §12.3.3: "the moving axes will be
//! relatively synchronized to the precision of microseconds").
//!
//! **ASSUMED** here, without a manual to confirm it:
//! * the 360 µs position-loop samples, and with them the PT segments, run on the motion clock,
//!   so the lock's rate correction moves them too;
//! * the first pair sets the clock (an offset: the samples do not jump), later ones steer its
//!   rate through a proportional-integral filter whose error decays within about 200 pairs;
//! * a pair more than [`REJECT_US`] off is ignored (a SYNC lost, so the Time Stamp met an
//!   older latch), unless [`REANCHOR_AFTER`] in a row are (the clock was set from a wrong pair:
//!   it is set again), and a pair more than [`STALE_US`] after the one before sets the clock
//!   again too, the filter keeping the rate it had;
//! * the correction is at most ±[`MAX_CORRECTION_PPM`];
//! * a stamp may come any time before the next SYNC (the manual's limit is not in the copy
//!   found).

/// Pairs over which the lock's error decays by about e (a double pole at `1 − 1/N`).
const POLE_PAIRS: f64 = 20.0;

/// A pair whose error exceeds this (µs) after the first is ignored.
pub const REJECT_US: i32 = 500;

/// This many pairs ignored in a row: the next one sets the clock again.
pub const REANCHOR_AFTER: u8 = 8;

/// A pair this long (µs) after the one before starts the filter over.
pub const STALE_US: u32 = 1_000_000;

/// The largest rate correction (ppm).
pub const MAX_CORRECTION_PPM: f64 = 1000.0;

/// A drive's motion clock: its oscillator's count plus an offset, and the lock's correction of
/// its rate.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MotionClock {
    /// Added to the oscillator's count (µs).
    offset_us: f64,
    /// The rate correction in force (ppm).
    correction_ppm: f64,
    /// The filter's integral term (ppm).
    integral_ppm: f64,
    /// The clock latched at the last SYNC (µs, wrapping).
    latched: Option<u32>,
    /// The master's time of the last pair taken (µs).
    last_stamp: Option<u32>,
    /// Pairs taken and ignored.
    pairs: (u32, u32),
    /// Pairs ignored since the last one taken.
    ignored_in_row: u8,
}

impl MotionClock {
    /// The rate correction in force (ppm; positive: faster).
    pub fn correction_ppm(&self) -> f64 {
        self.correction_ppm
    }

    /// Pairs taken into the lock, and pairs ignored.
    pub fn pairs(&self) -> (u32, u32) {
        self.pairs
    }

    /// A SYNC arrived when the oscillator had counted `oscillator_us`.
    pub fn latch(&mut self, oscillator_us: f64) {
        self.latched = Some(wrap(oscillator_us + self.offset_us));
    }

    /// A Time Stamp with the master's time `master_us` of the last SYNC. Returns the new rate
    /// correction (ppm) when it changed.
    pub fn stamp(&mut self, master_us: u32) -> Option<f64> {
        let latched = self.latched?;
        // Two's complement of the wrapped difference: the signed error.
        let error = latched.wrapping_sub(master_us) as i32;
        let interval = self.last_stamp.map(|last| master_us.wrapping_sub(last));
        let far_off = error.unsigned_abs() > REJECT_US.unsigned_abs();
        let anchored = self.ignored_in_row < REANCHOR_AFTER;
        match interval {
            Some(interval) if interval > 0 && interval < STALE_US && anchored => {
                if far_off {
                    self.pairs.1 = self.pairs.1.saturating_add(1);
                    self.ignored_in_row = self.ignored_in_row.saturating_add(1);
                    return None;
                }
                self.ignored_in_row = 0;
                self.pairs.0 = self.pairs.0.saturating_add(1);
                self.last_stamp = Some(master_us);
                Some(self.steer(f64::from(error), f64::from(interval)))
            }
            _ => {
                // The first pair (or the first after a long gap, or after many far off): set
                // the clock.
                self.offset_us -= f64::from(error);
                self.ignored_in_row = 0;
                self.latched = Some(master_us);
                self.last_stamp = Some(master_us);
                self.pairs.0 = self.pairs.0.saturating_add(1);
                None
            }
        }
    }

    /// One step of the filter: `error` µs ahead of the master after `interval` µs.
    fn steer(&mut self, error: f64, interval: f64) -> f64 {
        // Per pair a rate of 1 ppm moves the error by `gain` µs; gains for a double pole at
        // 1 − 1/N: proportional (2/N − 1/N²)/gain, integral 1/(N² gain).
        let gain = interval * 1e-6;
        let n = POLE_PAIRS;
        self.integral_ppm += error / (n * n * gain);
        self.integral_ppm = self
            .integral_ppm
            .clamp(-MAX_CORRECTION_PPM, MAX_CORRECTION_PPM);
        let proportional = error * (2.0 / n - 1.0 / (n * n)) / gain;
        self.correction_ppm =
            (-(proportional + self.integral_ppm)).clamp(-MAX_CORRECTION_PPM, MAX_CORRECTION_PPM);
        self.correction_ppm
    }
}

/// A clock value (µs) as the drive's 32-bit counter holds it.
fn wrap(us: f64) -> u32 {
    // Floor to whole microseconds (saturating in the float cast), then modulo 2³² by the
    // integer cast's truncation.
    libm::floor(us) as i64 as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A drive `ppm` fast, paired every `interval` µs of master time for `pairs` pairs: the
    /// largest error over the last `tail` pairs and the final correction.
    fn run(ppm: f64, interval: u32, pairs: u32, tail: u32) -> (f64, f64) {
        let mut clock = MotionClock::default();
        // The oscillator at the first SYNC: any value.
        let (mut oscillator, mut master) = (123_456_789.25, 4_000_000_000u32);
        let mut worst: f64 = 0.0;
        for k in 0..pairs {
            clock.latch(oscillator);
            let error = f64::from(clock.latched.unwrap().wrapping_sub(master) as i32);
            if k >= pairs - tail {
                worst = worst.max(error.abs());
            }
            clock.stamp(master);
            master = master.wrapping_add(interval);
            oscillator += f64::from(interval) * (1.0 + (ppm + clock.correction_ppm()) * 1e-6);
        }
        (worst, clock.correction_ppm())
    }

    #[test]
    fn a_fast_or_slow_drive_is_locked_within_two_hundred_pairs() {
        for ppm in [100.0, -100.0, 37.0, 0.0] {
            let (worst, correction) = run(ppm, 8640, 400, 200);
            // Whole microseconds: the error settles at the counter's resolution.
            assert!(worst <= 2.0, "{ppm} ppm: {worst} µs");
            assert!((correction + ppm).abs() < 5.0, "{ppm} ppm: {correction}");
        }
    }

    #[test]
    fn the_first_pair_sets_the_clock_and_the_counter_wraps() {
        let mut clock = MotionClock::default();
        clock.latch(10.0);
        assert_eq!(clock.stamp(u32::MAX - 5), None);
        // 8 µs later on both clocks: no error across the wrap.
        clock.latch(18.0);
        assert_eq!(clock.latched, Some(2));
        assert_eq!(clock.stamp(2), Some(0.0));
        assert_eq!(clock.pairs(), (2, 0));
    }

    #[test]
    fn a_pair_far_off_is_ignored_and_a_stamp_before_any_sync_too() {
        let mut clock = MotionClock::default();
        assert_eq!(clock.stamp(0), None);
        assert_eq!(clock.pairs(), (0, 0));
        clock.latch(0.0);
        clock.stamp(0);
        // A SYNC lost: the next stamp meets the old latch, one period off.
        assert_eq!(clock.stamp(4320), None);
        assert_eq!(clock.pairs(), (1, 1));
        assert_eq!(clock.correction_ppm(), 0.0);
    }

    #[test]
    fn a_clock_set_from_a_wrong_pair_is_set_again() {
        let mut clock = MotionClock::default();
        // The first stamp met a latch one period old: the clock is set 4320 µs ahead.
        clock.latch(0.0);
        clock.stamp(4320);
        let mut oscillator = 4320.0;
        let mut master = 4320u32;
        let mut errors = Vec::new();
        for _ in 0..12 {
            oscillator += 8640.0;
            master += 8640;
            clock.latch(oscillator);
            errors.push(clock.latched.unwrap().wrapping_sub(master) as i32);
            clock.stamp(master);
        }
        // Ignored, then set again after REANCHOR_AFTER: on time from then on.
        let reanchor = usize::from(REANCHOR_AFTER);
        assert!(errors[..=reanchor].iter().all(|&e| e == 4320), "{errors:?}");
        assert!(errors[reanchor + 1..].iter().all(|&e| e == 0), "{errors:?}");
        assert_eq!(clock.pairs().1, u32::from(REANCHOR_AFTER));
    }
}
