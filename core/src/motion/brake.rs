//! A stop as one number: a speed scale that falls from 1 to 0 within an acceleration budget
//! and, where the robot file limits jerk, a jerk budget.

/// The speed scale of a stop in progress. Whatever it scales — a generator's motion time (a
/// stop along the path) or a joint velocity (a stop in joint space) — decelerates by the same
/// fraction on every joint, so the direction of motion is kept while it comes to rest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Brake {
    /// The share of the speed at the start still left (1 → 0).
    scale: f64,
    /// How much the scale fell on the last tick.
    rate: f64,
}

impl Default for Brake {
    fn default() -> Self {
        Self {
            scale: 1.0,
            rate: 0.0,
        }
    }
}

impl Brake {
    /// A brake that starts from `scale` (0..=1) rather than full speed: a stop along a path
    /// that ran slower than planned (a Cartesian motion's time scale) brakes from the speed it
    /// had, instead of speeding it up to full scale at its first tick.
    pub fn at(scale: f64) -> Self {
        Self {
            scale: scale.clamp(0.0, 1.0),
            rate: 0.0,
        }
    }

    /// The next tick's scale. `max_rate`: the largest fall of the scale in one tick (from the
    /// acceleration limits at the speed being scaled); `max_change`: the largest change of that
    /// fall from one tick to the next (from the jerk limits; infinite without them). With a
    /// jerk budget the fall ramps up, and ramps down again before rest so that the scale
    /// reaches 0 with no deceleration left.
    pub fn next(&mut self, max_rate: f64, max_change: f64) -> f64 {
        let (max_rate, max_change) = (positive(max_rate), positive(max_change));
        let left = self.scale;
        let up = (self.rate + max_change).min(max_rate).min(left);
        let hold = self.rate.min(max_rate).min(left);
        let down = (self.rate - max_change).max(0.0);
        // What the scale still falls while the fall ramps down from `r` to nothing.
        let ramp_down = |r: f64| {
            if max_change.is_finite() {
                (r * r / (2.0 * max_change) - 0.5 * r).max(0.0)
            } else {
                0.0
            }
        };
        let rate = [up, hold]
            .into_iter()
            .find(|r| left - r >= ramp_down(*r))
            .unwrap_or(down)
            // Never a fall of nothing: a stop always ends.
            .max(max_change.min(max_rate).min(left) * 1e-3);
        self.rate = rate.min(left);
        self.scale = (left - rate).max(0.0);
        if self.scale < 1e-9 {
            self.scale = 0.0;
        }
        self.scale
    }

    /// The present scale.
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// Takes `scale` (between the one [`next`](Self::next) gave and `from`, the one before)
    /// instead: the caller found that the path slows down by itself and the scale need not fall
    /// as far. The fall is then the smaller one.
    pub fn ease_to(&mut self, scale: f64, from: f64) {
        self.scale = scale.clamp(0.0, 1.0);
        self.rate = (from - self.scale).max(0.0);
    }
}

/// `min_k limit_k · t / |v_k|`: how far a scale of `v` may change in a tick (∞ at rest).
pub fn budget(v: &[f64], limit: &[f64], t: f64) -> f64 {
    v.iter()
        .zip(limit)
        .map(|(v, l)| {
            let speed = libm::fabs(*v);
            if speed > 0.0 {
                l * t / speed
            } else {
                f64::INFINITY
            }
        })
        .fold(f64::INFINITY, f64::min)
}

/// A budget that is a positive number; anything else (0, NaN) allows the whole stop at once.
fn positive(v: f64) -> f64 {
    if v > 0.0 { v } else { f64::INFINITY }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn without_jerk_the_scale_falls_at_the_rate() {
        let mut b = Brake::default();
        let mut scales = [0.0; 5];
        for s in scales.iter_mut() {
            *s = b.next(0.25, f64::INFINITY);
        }
        assert_eq!(scales, [0.75, 0.5, 0.25, 0.0, 0.0]);
        assert_eq!(b.scale(), 0.0);
    }

    #[test]
    fn with_jerk_the_fall_ramps_up_and_down() {
        let mut b = Brake::default();
        let (mut last_rate, mut prev) = (0.0, 1.0);
        for _ in 0..200 {
            let s = b.next(0.1, 0.02);
            let rate = prev - s;
            assert!(rate <= 0.1 + 1e-12);
            assert!(
                (rate - last_rate).abs() <= 0.02 + 1e-12,
                "{rate} after {last_rate}"
            );
            (last_rate, prev) = (rate, s);
            if b.scale() == 0.0 {
                break;
            }
        }
        assert_eq!(b.scale(), 0.0);
        assert!(last_rate <= 0.02 + 1e-12);
    }
}
