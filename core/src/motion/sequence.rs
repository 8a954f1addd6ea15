//! Via-point sequences (spec §4.4), for Cartesian frames and for joint vectors.

use super::Refusal;

/// Number of via-point slots (indices 0..=19).
pub const VIA_SLOTS: usize = 20;
/// Failed reach checks after which a via point counts as missed (the seed's `8 < count++`).
const SETTLE_CHECKS: u32 = 10;

/// One stored via point and the minimum duration of the leg that ends at it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViaPoint<P> {
    /// The point (a frame or a joint vector).
    pub point: P,
    /// Minimum duration of the leg to this point (s, ≥ 0).
    pub min_duration: f64,
}

/// What the controller must do for a running sequence this tick.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SequenceStep<P> {
    /// Nothing: no sequence, a leg still running, or waiting for the arm to settle.
    Wait,
    /// Start the leg to this via point.
    MoveTo(ViaPoint<P>),
    /// The last via point was reached.
    Finished,
    /// A via point was not reached within the coarse tolerance: the sequence stops.
    Aborted,
}

/// Reach tolerances of a sequence (the seed: 0.002/0.1 for frames in m + rad, 0.001/0.05 for
/// joints).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerances {
    /// Below this the next leg starts at once.
    pub fine: f64,
    /// After ten failed checks, below this the sequence moves on anyway.
    pub coarse: f64,
}

/// Twenty via-point slots and the state of a running sequence.
///
/// A sequence runs the contiguous ready slots from 0 up to the first empty one. Starting it
/// copies those points and their blend tolerances, so slots may be rewritten while it runs
/// without affecting it.
///
/// Each slot has a blend tolerance (a default, or its own): a via point with a tolerance
/// above 0 is passed within it without stopping, the next leg blended in by the generator
/// ([`hand_over`](Self::hand_over)); with 0 the arm stops there and the reach check runs.
#[derive(Clone, Debug)]
pub struct Sequence<P> {
    slots: [Option<ViaPoint<P>>; VIA_SLOTS],
    tolerances: Tolerances,
    /// The blend tolerance of slots without their own.
    default_blend: f64,
    /// Slots' own blend tolerances.
    blends: [Option<f64>; VIA_SLOTS],
    run: Option<Run<P>>,
}

#[derive(Clone, Debug)]
struct Run<P> {
    points: [Option<ViaPoint<P>>; VIA_SLOTS],
    /// The blend tolerance at each point.
    blends: [f64; VIA_SLOTS],
    /// Index of the leg's target that is running or just completed.
    current: usize,
    failed_checks: u32,
    /// The generator declined to blend at `current` (not worth it): stop there.
    declined: bool,
}

impl<P: Copy> Run<P> {
    /// The point after via point `index` if the sequence blends at `index`.
    fn towards(&self, index: usize) -> Option<P> {
        let blends = self.blends.get(index).is_some_and(|t| *t > 0.0);
        let next = self.points.get(index + 1).copied().flatten();
        next.filter(|_| blends).map(|via| via.point)
    }
}

impl<P: Copy> Sequence<P> {
    /// Empty slots, blending with `default_blend` (≥ 0; 0 stops at every via point).
    pub fn new(tolerances: Tolerances, default_blend: f64) -> Self {
        Self {
            slots: [None; VIA_SLOTS],
            tolerances,
            default_blend,
            blends: [None; VIA_SLOTS],
            run: None,
        }
    }

    /// Sets the blend tolerance of slot `index` (`None`: the default again). Refused unless
    /// finite and ≥ 0.
    pub fn set_blend(&mut self, index: usize, tolerance: Option<f64>) -> Result<(), Refusal> {
        if tolerance.is_some_and(|t| !(t.is_finite() && t >= 0.0)) {
            return Err(Refusal::InvalidNumber);
        }
        let slot = self.blends.get_mut(index).ok_or(Refusal::IndexOutOfRange)?;
        *slot = tolerance;
        Ok(())
    }

    /// The blend tolerance in effect for slot `index`.
    pub fn blend(&self, index: usize) -> Result<f64, Refusal> {
        let own = self.blends.get(index).ok_or(Refusal::IndexOutOfRange)?;
        Ok(own.unwrap_or(self.default_blend))
    }

    /// Stores via point `index` (the seed wrote out of bounds for indices ≥ 128, spec §9 item
    /// 19; every index ≥ 20 is refused here).
    pub fn set(&mut self, index: usize, via: ViaPoint<P>) -> Result<(), Refusal> {
        let slot = self.slots.get_mut(index).ok_or(Refusal::IndexOutOfRange)?;
        *slot = Some(via);
        Ok(())
    }

    /// Empties every slot and forgets the slots' own blend tolerances; true if there was
    /// anything to forget.
    pub fn clear(&mut self) -> bool {
        let had = self.slots.iter().any(Option::is_some) || self.blends.iter().any(Option::is_some);
        self.slots = [None; VIA_SLOTS];
        self.blends = [None; VIA_SLOTS];
        had
    }

    /// Starts the sequence; returns the first leg to command.
    pub fn start(&mut self) -> Result<ViaPoint<P>, Refusal> {
        self.start_planned(&[])
    }

    /// [`start`](Self::start), each leg `k` lasting at least `durations[k]` (s) as well as its
    /// own minimum: what the up-front check of the legs found they need (`reach.rs`).
    pub fn start_planned(&mut self, durations: &[f64]) -> Result<ViaPoint<P>, Refusal> {
        if self.run.is_some() {
            return Err(Refusal::Busy);
        }
        let first = self
            .slots
            .first()
            .copied()
            .flatten()
            .ok_or(Refusal::NoGoal)?;
        let planned = |via: ViaPoint<P>, k: usize| ViaPoint {
            min_duration: durations
                .get(k)
                .map_or(via.min_duration, |d| via.min_duration.max(*d)),
            ..via
        };
        let first = planned(first, 0);
        let mut points = [None; VIA_SLOTS];
        // The contiguous prefix of ready slots (all 20 if every slot is ready, spec §9 item 21).
        for (k, (dst, src)) in points
            .iter_mut()
            .zip(&self.slots)
            .take_while(|(_, s)| s.is_some())
            .enumerate()
        {
            *dst = src.map(|via| planned(via, k));
        }
        let blends = self.blends.map(|own| own.unwrap_or(self.default_blend));
        self.run = Some(Run {
            points,
            blends,
            current: 0,
            failed_checks: 0,
            declined: false,
        });
        Ok(first)
    }

    /// The via points a [`start`](Self::start) would run: slots 0.. up to the first empty one.
    pub fn ready(&self) -> impl Iterator<Item = &ViaPoint<P>> {
        self.slots.iter().map_while(Option::as_ref)
    }

    /// Stops the sequence at once (the generator is stopped separately).
    pub fn halt(&mut self) {
        self.run = None;
    }

    /// True while a sequence runs.
    pub fn is_running(&self) -> bool {
        self.run.is_some()
    }

    /// Blends the next leg into the running one if the via point it runs to has a blend
    /// tolerance: `blend(next via point, tolerance, the point after it if the sequence blends
    /// there too)` queues it in the generator, with the tolerance limited to
    /// `margin(via point)` (how far the path may stray there, e.g. to a joint or workspace
    /// limit). `blend` says whether it queued the leg; if not (the blend was not worth it), the
    /// sequence stops at the via point as with tolerance 0 and does not ask again. Does nothing
    /// unless `ready`: the leg's generator runs and accepts a next leg. The blended via point
    /// is not reach-checked: the arm only passes it.
    pub fn hand_over(
        &mut self,
        ready: bool,
        margin: impl FnOnce(&P) -> f64,
        blend: impl FnOnce(ViaPoint<P>, f64, Option<P>) -> Result<bool, Refusal>,
    ) {
        let Some(run) = self.run.as_mut().filter(|r| ready && !r.declined) else {
            return;
        };
        let (Some(Some(corner)), Some(Some(next)), Some(tolerance)) = (
            run.points.get(run.current),
            run.points.get(run.current + 1),
            run.blends.get(run.current),
        ) else {
            return;
        };
        let tolerance = tolerance.min(margin(&corner.point));
        let then = run.towards(run.current + 1);
        if tolerance > 0.0 {
            match blend(*next, tolerance, then) {
                Ok(true) => {
                    run.current += 1;
                    run.failed_checks = 0;
                }
                Ok(false) | Err(_) => run.declined = true,
            }
        }
    }

    /// The via point after the running leg's target if the sequence will blend there (its
    /// tolerance is above 0): a leg that blends at its end is planned for it (the generators'
    /// `move_towards`).
    pub fn towards(&self) -> Option<P> {
        self.run.as_ref().and_then(|run| run.towards(run.current))
    }

    /// Steps the sequence once the leg's generator is idle: checks how far the arm is from the
    /// via point just completed (`error_of`) and says what to do next.
    pub fn poll(&mut self, leg_done: bool, error_of: impl FnOnce(&P) -> f64) -> SequenceStep<P> {
        let Some(run) = &mut self.run else {
            return SequenceStep::Wait;
        };
        if !leg_done {
            return SequenceStep::Wait;
        }
        let Some(Some(done)) = run.points.get(run.current) else {
            self.run = None;
            return SequenceStep::Finished;
        };
        let error = error_of(&done.point);
        let next = run.points.get(run.current + 1).copied().flatten();
        let reached = error < self.tolerances.fine;
        if !reached {
            run.failed_checks += 1;
            if run.failed_checks < SETTLE_CHECKS {
                return SequenceStep::Wait;
            }
            if error.is_nan() || error >= self.tolerances.coarse {
                self.run = None;
                return SequenceStep::Aborted;
            }
        }
        // Reached, or close enough after settling: move on. The seed's coarse branch advanced
        // the index without commanding the next leg, skipping it (spec §9 item 21).
        match next {
            Some(via) => {
                run.current += 1;
                run.failed_checks = 0;
                run.declined = false;
                SequenceStep::MoveTo(via)
            }
            None => {
                self.run = None;
                SequenceStep::Finished
            }
        }
    }
}
