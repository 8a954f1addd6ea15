//! Blending consecutive straight legs through a via point without stopping.
//!
//! The seed stops at every via point (spec §4.4). A blend starts the next leg before the
//! current one has ended and *superposes* them: while both run, the set-point is the next
//! leg's point plus the way the current leg still has to go (its point minus its goal). Both
//! legs are rest-to-rest profiles, so the sum is continuous in position and velocity (and in
//! acceleration when the profiles are), and it is exactly the current leg before the overlap
//! and exactly the next leg after it.
//!
//! The overlap starts at the earliest time `t_s` on the current leg's clock at which
//!
//! * the current leg's remaining way at `t_s` and the next leg's way by the current leg's end
//!   are each within the tolerance. Then so is every set-point of the overlap: its distance
//!   from the via point is at most the sum of the two legs' ways from it (triangle
//!   inequality), a convex function of time (the current leg is slowing down and the next
//!   speeding up), so largest at the overlap's ends, where one of the two is zero;
//! * per axis, the current leg's speed at `t_s` plus the next leg's speed at the end of the
//!   overlap stays within the axis's velocity limit. The overlap lies in the second half of
//!   the current leg and the first half of the next (symmetric profiles: slowing down and
//!   speeding up respectively), so those two speeds bound the sum throughout.
//!
//! Every condition only gets easier as `t_s` grows and all hold at the current leg's end, so
//! `t_s` is found by bisection with a fixed number of steps. A blend that would not save time
//! or would overlap for less than a control period is not made
//! ([`LegChain::queue_if_worthwhile`]): the sequence stops at that via point as it does with tolerance 0. Accelerations cannot be traded
//! against `t_s`: the next leg is instead planned within what the current leg's acceleration
//! leaves of each axis's limit ([`acceleration_budget`]). Nor can jerks: a leg whose end blends
//! is planned with half the jerk on the axes the next leg shares ([`jerk_towards`]), the next
//! within the rest ([`jerk_budget`]).

use super::Refusal;
use super::straight_line::StraightLine;

/// Bisection steps for the blend start: 2⁻⁶⁰ of the leg's duration.
const BISECTION_STEPS: usize = 60;
/// Relative slack on a velocity limit (the bar the profiles are checked against): a leg that
/// starts from an IK solution's FK has direction components of ~1e-10 on axes it does not
/// really move along, which must not forbid the next leg to cruise there at the limit.
const SPEED_SLACK: f64 = 1e-9;

/// A leg of a blended chain: anything with a duration.
pub(crate) trait Leg: Copy {
    /// Duration of the leg (s).
    fn duration(&self) -> f64;
}

/// Which legs make the set-point at some time.
pub(crate) struct Blended<'a, L> {
    /// The leg whose point is the set-point, and the time on its clock.
    pub lead: (&'a L, f64),
    /// A leg still finishing, and the time on its clock: its remaining way (its point minus
    /// its goal) is added to the lead's point.
    pub residual: Option<(&'a L, f64)>,
}

/// The running leg, the one it blends out of and the one it will blend into.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LegChain<L> {
    leg: L,
    /// Time on the running leg's clock (s).
    elapsed: f64,
    /// The previous leg and the time on its clock when this one started.
    tail: Option<(L, f64)>,
    /// The next leg and the time on this leg's clock at which it starts.
    next: Option<(L, f64)>,
}

impl<L: Leg> LegChain<L> {
    /// A chain of one leg, at its start.
    pub fn new(leg: L) -> Self {
        Self {
            leg,
            elapsed: 0.0,
            tail: None,
            next: None,
        }
    }

    /// The running leg.
    pub fn leg(&self) -> &L {
        &self.leg
    }

    /// Time reached on the running leg's clock.
    pub fn elapsed(&self) -> f64 {
        self.elapsed
    }

    /// True if a next leg may be queued: none is queued yet.
    pub fn accepts_next(&self) -> bool {
        self.next.is_none()
    }

    /// Queues `next` to start at `start` on the running leg's clock (not before now, nor after
    /// the running leg's end).
    pub fn queue(&mut self, next: L, start: f64) -> Result<(), Refusal> {
        if self.next.is_some() {
            return Err(Refusal::Busy);
        }
        let start = start.max(self.elapsed).min(self.leg.duration());
        self.next = Some((next, start));
        Ok(())
    }

    /// Queues the next leg if a blend is worth it (`Ok(true)`): `budgeted`, the next leg planned
    /// within what the running leg leaves of the limits and its start on the running leg's
    /// clock, must end earlier than the `full` leg (planned alone) would after a stop (a tight
    /// budget can make a blend slower than stopping), and overlap the running leg for at least
    /// `min_overlap` (a control period: a shorter overlap falls between two set-points, which
    /// would then cut the corner by their chord, not within the tolerance). If not
    /// (`Ok(false)`), the sequence stops at the via point as with tolerance 0.
    pub fn queue_if_worthwhile(
        &mut self,
        full: &L,
        budgeted: Option<(L, f64)>,
        min_overlap: f64,
    ) -> Result<bool, Refusal> {
        let current = self.leg.duration();
        match budgeted {
            Some((next, start))
                if start + next.duration() < current + full.duration()
                    && current - start >= min_overlap =>
            {
                self.queue(next, start).map(|()| true)
            }
            _ => Ok(false),
        }
    }

    /// The legs that make the set-point at time `t` on the running leg's clock.
    pub fn at(&self, t: f64) -> Blended<'_, L> {
        if let Some((next, start)) = &self.next
            && t >= *start
        {
            return Blended {
                lead: (next, t - start),
                residual: Some((&self.leg, t)),
            };
        }
        Blended {
            lead: (&self.leg, t),
            residual: self
                .tail
                .as_ref()
                .map(|(tail, offset)| (tail, t + offset))
                .filter(|(tail, time)| *time < tail.duration()),
        }
    }

    /// True while the running leg alone makes the set-point: no leg finishing under it, none
    /// queued to blend into.
    pub fn is_alone(&self) -> bool {
        self.tail.is_none() && self.next.is_none()
    }

    /// True if the whole chain has ended by time `t` (the tail always ends before the leg).
    pub fn ended_at(&self, t: f64) -> bool {
        self.next.is_none() && t >= self.leg.duration()
    }

    /// Advances to time `t` on the running leg's clock, switching to the next leg once it has
    /// started.
    pub fn commit(&mut self, t: f64) {
        self.elapsed = t;
        if let Some((next, start)) = self.next
            && t >= start
        {
            self.tail = Some((self.leg, start));
            self.leg = next;
            self.elapsed = t - start;
            self.next = None;
        }
        if self
            .tail
            .is_some_and(|(tail, offset)| self.elapsed + offset >= tail.duration())
        {
            self.tail = None;
        }
    }
}

/// One group of axes of a blend: the same straight line of the current and of the next leg
/// (e.g. the translation) and the axes' velocity limits.
pub(crate) struct Axes<'a> {
    /// The current leg's line, stretched to its leg's duration.
    pub current: &'a StraightLine,
    /// The next leg's line, stretched to its leg's duration.
    pub next: &'a StraightLine,
    /// Velocity limit per axis.
    pub v_max: &'a [f64],
}

/// The time on the current leg's clock (of `current_duration`) at which the next leg (of
/// `next_duration`) may start so that the blend stays within `tolerance` of the via point and
/// within the velocity limits (see the module doc); not before `not_before`. The current leg's
/// end (no overlap) if the tolerance is 0 or not a number.
pub(crate) fn blend_start(
    axes: &[Axes<'_>],
    current_duration: f64,
    next_duration: f64,
    tolerance: f64,
    not_before: f64,
) -> f64 {
    let end = current_duration;
    let fits = |t: f64| {
        let overlap = end - t;
        let (mut remaining, mut travelled) = (0.0, 0.0);
        let mut fast = false;
        for group in axes {
            remaining += group.current.length() - group.current.progress(t);
            travelled += group.next.progress(overlap);
            let (v_current, v_next) = (group.current.speed(t), group.next.speed(overlap));
            fast |= group
                .current
                .direction()
                .iter()
                .zip(group.next.direction())
                .zip(group.v_max)
                .any(|((a, b), v)| {
                    v_current * libm::fabs(*a) + v_next * libm::fabs(*b) > v * (1.0 + SPEED_SLACK)
                });
        }
        !fast && remaining <= tolerance && travelled <= tolerance
    };
    let earliest = (end / 2.0).max(end - next_duration / 2.0).max(not_before);
    let overlap_possible = tolerance > 0.0 && earliest < end;
    if !overlap_possible {
        return end;
    }
    if fits(earliest) {
        return earliest;
    }
    // `fits` is false at `lo` and true at `hi` (at the end both legs are at the via point and
    // at rest).
    let (mut lo, mut hi) = (earliest, end);
    for _ in 0..BISECTION_STEPS {
        let mid = 0.5 * (lo + hi);
        if fits(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

/// What the current leg's acceleration leaves of each axis's limit `a_max` for a next leg in
/// direction `next_direction`, written to `budget`: planned within it, the sum of both legs'
/// accelerations stays within `a_max` while they overlap. In the overlap the current leg
/// slows down (its acceleration opposes its direction) and the next speeds up (along its
/// own), so on an axis the next leg moves along in the same sense the two accelerations have
/// opposite signs and the larger alone bounds the sum: the full limit is left. Only an axis
/// that reverses needs to share it.
pub(crate) fn acceleration_budget(
    current: &StraightLine,
    next_direction: &[f64],
    a_max: &[f64],
    budget: &mut [f64],
) {
    let peak = current.peak_acceleration();
    share(peak, current, next_direction, a_max, budget, |d, e| {
        d * e < 0.0
    });
}

/// What the current leg's jerk leaves of each axis's limit `j_max` for a next leg in direction
/// `next_direction`, written to `budget`. Jerks change sign within both halves of a
/// jerk-limited profile, so on every axis both legs move along the limit is shared.
pub(crate) fn jerk_budget(
    current: &StraightLine,
    next_direction: &[f64],
    j_max: &[f64],
    budget: &mut [f64],
) {
    let peak = current.peak_jerk();
    share(peak, current, next_direction, j_max, budget, |d, e| {
        d != 0.0 && e != 0.0
    });
}

/// Jerk limits for a leg (direction `own`) whose end blends into a next leg (direction
/// `next`), written to `out`: halved on the axes both move along. The next leg is planned
/// within what this one leaves ([`jerk_budget`]), so each gets half there and their jerks,
/// which change sign within each half of a jerk-limited profile and so cannot be relied on to
/// cancel, add up to at most the limit. Axes only one of them moves along keep the whole.
pub(crate) fn jerk_towards(j_max: &[f64], own: &[f64], next: &[f64], out: &mut [f64]) {
    for (((o, j), d), e) in out.iter_mut().zip(j_max).zip(own).zip(next) {
        *o = if *d != 0.0 && *e != 0.0 { 0.5 * j } else { *j };
    }
}

/// `budget = limit − peak·|d|` on the axes where `shared(d, e)` says the two legs' values add
/// (d, e: the current and the next leg's direction components), the whole limit elsewhere.
#[inline(never)]
fn share(
    peak: f64,
    current: &StraightLine,
    next_direction: &[f64],
    limit: &[f64],
    budget: &mut [f64],
    shared: impl Fn(f64, f64) -> bool,
) {
    for (((b, l), d), e) in budget
        .iter_mut()
        .zip(limit)
        .zip(current.direction())
        .zip(next_direction)
    {
        *b = if shared(*d, *e) {
            (l - peak * libm::fabs(*d)).max(0.0)
        } else {
            *l
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone, Copy, Debug, PartialEq)]
    struct Span(f64);

    impl Leg for Span {
        fn duration(&self) -> f64 {
            self.0
        }
    }

    #[test]
    fn a_chain_switches_legs_at_the_start_of_the_next_and_drops_the_finished_tail() {
        let mut chain = LegChain::new(Span(2.0));
        chain.queue(Span(3.0), 1.5).unwrap();
        assert_eq!(chain.queue(Span(1.0), 1.8), Err(Refusal::Busy));
        let before = chain.at(1.0);
        assert_eq!((before.lead.0, before.lead.1), (&Span(2.0), 1.0));
        assert!(before.residual.is_none());
        let during = chain.at(1.75);
        assert_eq!((during.lead.0, during.lead.1), (&Span(3.0), 0.25));
        assert_eq!(
            during.residual.map(|(l, t)| (*l, t)),
            Some((Span(2.0), 1.75))
        );
        chain.commit(1.75);
        assert_eq!(chain.leg(), &Span(3.0));
        assert_eq!(chain.elapsed(), 0.25);
        assert!(chain.accepts_next());
        assert_eq!(chain.at(0.4).residual.map(|(_, t)| t), Some(1.9));
        chain.commit(0.5);
        assert!(chain.at(0.6).residual.is_none());
        assert!(!chain.ended_at(2.9));
        assert!(chain.ended_at(3.0));
    }

    #[test]
    fn a_queued_leg_never_starts_after_the_running_one_ends() {
        let mut chain = LegChain::new(Span(1.0));
        chain.queue(Span(1.0), 7.0).unwrap();
        assert!(!chain.ended_at(1.0));
        assert_eq!(chain.at(1.0).lead.1, 0.0);
    }

    /// Two unit legs at right angles (x then y), 1 m/s, 1 m/s².
    fn corner() -> (StraightLine, StraightLine) {
        let limits = [1.0, 1.0];
        (
            StraightLine::plan(&[0.0, 0.0], &[1.0, 0.0], &limits, &limits),
            StraightLine::plan(&[1.0, 0.0], &[1.0, 1.0], &limits, &limits),
        )
    }

    #[test]
    fn the_blend_starts_where_the_remaining_way_is_the_tolerance() {
        let (a, b) = corner();
        let axes = [Axes {
            current: &a,
            next: &b,
            v_max: &[1.0, 1.0],
        }];
        // A triangle profile of 2 s: the last 0.1 m take √0.2 s.
        let start = blend_start(&axes, a.duration(), b.duration(), 0.1, 0.0);
        assert!((start - (2.0 - 0.2f64.sqrt())).abs() < 1e-12, "{start}");
        assert_eq!(blend_start(&axes, 2.0, 2.0, 0.0, 0.0), 2.0);
        assert_eq!(blend_start(&axes, 2.0, 2.0, f64::NAN, 0.0), 2.0);
        // A huge tolerance: from halfway, where speeds (1 + 0 at the start of the overlap)
        // fit the limit.
        assert_eq!(blend_start(&axes, 2.0, 2.0, 10.0, 0.0), 1.0);
        assert_eq!(blend_start(&axes, 2.0, 2.0, 10.0, 1.5), 1.5);
    }

    #[test]
    fn a_blend_along_one_axis_keeps_the_summed_speed_within_the_limit() {
        // x then further along x: speeds add on the same axis.
        let limits = [1.0];
        let a = StraightLine::plan(&[0.0], &[4.0], &limits, &limits);
        let b = StraightLine::plan(&[4.0], &[8.0], &limits, &limits);
        let axes = [Axes {
            current: &a,
            next: &b,
            v_max: &limits,
        }];
        let start = blend_start(&axes, a.duration(), b.duration(), 10.0, 0.0);
        let overlap = a.duration() - start;
        assert!(a.speed(start) + b.speed(overlap) <= 1.0 + 1e-9);
        // Both at 1 m/s² on x: the speeds sum to 2·(5 − t) ≤ 1 from t = 4.5 s.
        assert!((overlap - 0.5).abs() < 1e-9, "{overlap}");
    }

    #[test]
    fn jerk_is_shared_on_every_axis_both_legs_use() {
        let limits = [1.0, 1.0];
        let (a, _) = corner();
        let mut budget = [0.0; 2];
        // A trapezoid has no jerk limit to share.
        jerk_budget(&a, &[0.6, 0.8], &[2.0, 2.0], &mut budget);
        assert_eq!(budget, [2.0, 2.0]);
        let jerky = StraightLine::plan_jerk_limited(
            &[0.0, 0.0],
            &[3.0, 4.0],
            &limits,
            &limits,
            &[1.0, 2.0],
        )
        .unwrap();
        // Path jerk limit min(1/0.6, 2/0.8) = 5/3: 1 on x, 4/3 on y.
        jerk_budget(&jerky, &[0.0, 1.0], &[2.0, 2.0], &mut budget);
        assert!(
            (budget[0] - 2.0).abs() < 1e-12 && (budget[1] - 2.0 / 3.0).abs() < 1e-12,
            "{budget:?}"
        );
        jerk_budget(&jerky, &[-1.0, 0.0], &[2.0, 2.0], &mut budget);
        assert!(
            (budget[0] - 1.0).abs() < 1e-12 && budget[1] == 2.0,
            "{budget:?}"
        );
    }

    #[test]
    fn a_leg_towards_a_blend_halves_the_jerk_on_shared_axes() {
        let mut out = [0.0; 3];
        jerk_towards(
            &[2.0, 4.0, 6.0],
            &[0.6, 0.8, 0.0],
            &[0.0, -1.0, 0.0],
            &mut out,
        );
        assert_eq!(out, [2.0, 2.0, 6.0]);
    }

    #[test]
    fn the_budget_is_shared_only_on_axes_that_reverse() {
        // The current leg: x at its 1 m/s² peak.
        let (a, _) = corner();
        let mut budget = [0.0; 2];
        acceleration_budget(&a, &[0.0, 1.0], &[1.0, 2.0], &mut budget);
        assert_eq!(budget, [1.0, 2.0]);
        acceleration_budget(&a, &[0.6, 0.8], &[1.0, 2.0], &mut budget);
        assert_eq!(budget, [1.0, 2.0]);
        acceleration_budget(&a, &[-0.6, 0.8], &[1.5, 2.0], &mut budget);
        assert_eq!(budget, [0.5, 2.0]);
    }
}
