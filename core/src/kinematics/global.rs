//! Global IK: the closed form's exact solution nearest the seed where the chain has one;
//! otherwise descents ([`descent`](super::descent)) from the seed and then from deterministic
//! random configurations, restarted early when an attempt stops making progress.

use super::chain::Chain;
use super::descent::Bounds;
use super::evaluation::LastEvaluation;
use super::ik::{IkError, IkResult, IkSolution};
use crate::MAX_JOINTS;
use crate::config::IkConfig;
use crate::math::{self, Frame};
use crate::rng::SplitMix64;

/// Iterations of one global attempt before it restarts from a new random seed.
const ATTEMPT_ITERATIONS: u16 = 30;
/// A best effort within this error (m + rad) is finished by undamped Newton steps.
const CLOSE: f64 = 1e-5;

impl Chain {
    /// Global IK. A chain of a closed-form family takes the exact solution nearest `seed` if
    /// there is one. Otherwise (and for every other chain) it descends from `seed`, then from
    /// deterministic random configurations drawn with `rng_seed`, until one converges within
    /// the limits or `config.global_iterations` iterations are spent. The same inputs always
    /// give the same answer.
    pub fn solve_global(
        &self,
        target: &Frame,
        seed: &[f64],
        config: &IkConfig,
        rng_seed: u64,
    ) -> Result<IkResult, IkError> {
        if self.closed_form().is_some()
            && let Some(found) = self.nearest_exact(target, seed, None)?
            && let Some(solution) = found.within(config.tolerance)
        {
            return Ok(IkResult::Converged(solution));
        }
        let mut search = self.global_search(target, seed, config, rng_seed)?;
        // One slice of the whole budget: every attempt fits.
        Ok(self.finish_search(&mut search, config.global_iterations, &mut quiet))
    }

    /// `result`, or if its best pose is within [`CLOSE`] but not converged, that pose taken
    /// to full precision by [`sharpen`](Self::sharpen): within ~0.05 rad of two singularities
    /// at once the damped steps crawl, and every attempt that gets there runs out of steps
    /// 1e-7 from the target.
    fn finished(&self, target: &Frame, result: IkResult, tolerance: f64) -> IkResult {
        let IkResult::NotConverged(best) = result else {
            return result;
        };
        if score(&best) > CLOSE {
            return result;
        }
        let mut q = best.q;
        self.sharpen(target, &mut q);
        let e = math::diff(&self.pose(&q), target);
        let (position_error, orientation_error) =
            (e.fixed_rows::<3>(0).norm(), e.fixed_rows::<3>(3).norm());
        if position_error < tolerance && orientation_error < tolerance {
            IkResult::Converged(IkSolution {
                q,
                position_error,
                orientation_error,
                ..best
            })
        } else {
            result
        }
    }

    /// A global search from `seed` to `target` (no closed form tried), to be run in slices by
    /// [`continue_search`](Self::continue_search): the same attempts, in the same order, with
    /// the same answer as [`solve_global`](Self::solve_global) on a chain without one.
    pub fn global_search(
        &self,
        target: &Frame,
        seed: &[f64],
        config: &IkConfig,
        rng_seed: u64,
    ) -> Result<GlobalSearch, IkError> {
        let mut start = [0.0; MAX_JOINTS];
        self.prepare(target, seed, &mut start)?;
        Ok(GlobalSearch {
            target: *target,
            tolerance: config.tolerance,
            q: start,
            rng: SplitMix64::new(rng_seed),
            budget: config.global_iterations,
            best: None,
            used: 0,
        })
    }

    /// Runs `search` on for at most `slice` Newton steps (at least [`ATTEMPT_ITERATIONS`]
    /// make progress: a slice ends between attempts); its answer once it has converged or
    /// spent its budget, `None` while it goes on.
    pub fn continue_search(&self, search: &mut GlobalSearch, slice: u16) -> Option<IkResult> {
        self.continue_search_counted(search, slice, &mut quiet)
    }

    /// [`continue_search`](Self::continue_search) until the answer, in slices of `slice`.
    fn finish_search(
        &self,
        search: &mut GlobalSearch,
        slice: u16,
        on_step: &mut impl FnMut(),
    ) -> IkResult {
        // Every slice spends at least one step of the budget, so this bound is never reached.
        for _ in 0..=search.budget {
            if let Some(answer) = self.continue_search_counted(search, slice, on_step) {
                return answer;
            }
        }
        IkResult::NotConverged(search.best_or_seed(self, on_step))
    }

    /// [`continue_search`](Self::continue_search), calling `on_step` once per Newton step
    /// taken, so a test can count the work independently of the reported `iterations`.
    fn continue_search_counted(
        &self,
        search: &mut GlobalSearch,
        slice: u16,
        on_step: &mut impl FnMut(),
    ) -> Option<IkResult> {
        let passes = slice.max(ATTEMPT_ITERATIONS);
        let mut left = passes;
        let mut last = LastEvaluation::default();
        // Each attempt spends at least one step of `left`: with one pass more than it has, the
        // loop always ends at a `return` or a `break`.
        for _ in 0..=passes {
            let limit = search.budget.min(ATTEMPT_ITERATIONS);
            if limit == 0 {
                break;
            }
            if limit > left {
                return None;
            }
            let target = &search.target;
            let bounds = (Bounds::Wrapping, &mut last);
            let descent = self.descend(target, search.q, limit, search.tolerance, bounds, on_step);
            search.used += descent.steps;
            // The steps actually taken (at most `limit`), not the index of the best pose: the
            // budget bounds the work. An attempt takes at least one step unless it converged.
            let spent = u16::try_from(descent.steps).unwrap_or(u16::MAX).max(1);
            search.budget = search.budget.saturating_sub(spent);
            left = left.saturating_sub(spent);
            let mut found = descent.best;
            found.iterations = search.used;
            if descent.converged {
                return Some(IkResult::Converged(found));
            }
            if search.best.is_none_or(|b| score(&found) < score(&b)) {
                search.best = Some(found);
            }
            if search.budget == 0 {
                break;
            }
            search.q = self.random_configuration(&mut search.rng);
        }
        let answer = IkResult::NotConverged(search.best_or_seed(self, on_step));
        Some(self.finished(&search.target, answer, search.tolerance))
    }

    /// A configuration drawn uniformly within the limits (revolute ranges capped at ±π about
    /// their centre: a wider range only repeats the same poses).
    fn random_configuration(&self, rng: &mut SplitMix64) -> [f64; MAX_JOINTS] {
        let mut q = [0.0; MAX_JOINTS];
        let (min, max) = self.limits();
        for (i, (v, (lo, hi))) in q.iter_mut().zip(min.iter().zip(max)).enumerate() {
            let (lo, hi) = if self.is_prismatic(i) {
                (*lo, *hi)
            } else {
                let mid = 0.5 * (lo + hi);
                (
                    lo.max(mid - core::f64::consts::PI),
                    hi.min(mid + core::f64::consts::PI),
                )
            };
            *v = rng.uniform(lo, hi);
        }
        q
    }
}

/// A global search between slices ([`Chain::global_search`]): its target, the attempt to
/// make next, the budget left and the best pose so far.
#[derive(Clone, Debug)]
pub struct GlobalSearch {
    target: Frame,
    tolerance: f64,
    /// The start of the next attempt.
    q: [f64; MAX_JOINTS],
    rng: SplitMix64,
    /// Newton steps left.
    budget: u16,
    best: Option<IkSolution>,
    /// Newton steps taken.
    used: u32,
}

impl GlobalSearch {
    /// The best pose found, or with no attempt made (a zero budget) the clamped seed.
    fn best_or_seed(&self, chain: &Chain, on_step: &mut impl FnMut()) -> IkSolution {
        let mut best = self.best.unwrap_or_else(|| {
            let bounds = (Bounds::Wrapping, &mut LastEvaluation::default());
            let seed = chain.descend(&self.target, self.q, 0, self.tolerance, bounds, on_step);
            seed.best
        });
        best.iterations = self.used;
        best
    }
}

/// The step hook of every search outside tests: one function, so that the search and its
/// descents are compiled once (a closure of each caller's would be a copy of each).
fn quiet() {}

/// The seed's mixed metric: metres plus radians.
fn score(s: &IkSolution) -> f64 {
    s.position_error + s.orientation_error
}
#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::math::{Rotation3, Vector3};

    fn ranger() -> (Chain, IkConfig) {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../robots/ranger-mk1.toml");
        let config = crate::config::load_file(path).unwrap();
        (Chain::new(&config), config.ik)
    }

    /// The budget bounds the Newton steps actually taken, counted by the solver's step hook
    /// rather than read back from the reported `iterations`.
    #[test]
    fn global_budget_bounds_the_steps_taken() {
        let (chain, ik) = ranger();
        for budget in [1, 29, 30, 31, 300] {
            let ik = IkConfig {
                global_iterations: budget,
                ..ik
            };
            for k in 0..20u32 {
                // 4 m out: beyond the ~1.5 m reach, so every attempt runs until it stalls or
                // exhausts its share and the whole budget is spent.
                let turn = Vector3::new(0.1 * f64::from(k), -0.3, 0.7);
                let target =
                    Frame::from_parts(Vector3::new(-0.5, 4.0, 0.7).into(), Rotation3::new(turn));
                let mut steps = 0u32;
                let mut search = chain
                    .global_search(&target, &chain.mid_range(), &ik, u64::from(k))
                    .unwrap();
                let result = chain.finish_search(&mut search, budget, &mut || steps += 1);
                assert!(!result.is_converged());
                assert_eq!(steps, u32::from(budget), "budget {budget}, seed {k}");
                assert_eq!(result.solution().iterations, steps);
            }
        }
    }

    /// A converged global solve reports the steps of every attempt, not just the last one's.
    #[test]
    fn global_iterations_count_every_attempt() {
        let (chain, ik) = ranger();
        let mut rng = crate::rng::SplitMix64::new(3);
        for k in 0..200 {
            let q = chain.random_joints(&mut rng);
            let target = chain.forward(&q).unwrap();
            let mut steps = 0u32;
            let mut search = chain
                .global_search(&target, &chain.mid_range(), &ik, k)
                .unwrap();
            let result = chain.finish_search(&mut search, ik.global_iterations, &mut || steps += 1);
            assert_eq!(result.solution().iterations, steps);
            assert!(steps <= u32::from(ik.global_iterations));
        }
    }

    /// In slices, the search takes at most a slice's steps at a time (at least one attempt's)
    /// and gives exactly the answer of the whole search: reachable targets and unreachable.
    #[test]
    fn a_search_in_slices_is_bounded_per_slice_and_gives_the_same_answer() {
        let (chain, ik) = ranger();
        let ik = IkConfig {
            global_iterations: 400,
            ..ik
        };
        let mut rng = crate::rng::SplitMix64::new(7);
        let mut reached = 0;
        for k in 0..40u64 {
            let target = if k % 2 == 0 {
                chain.forward(&chain.random_joints(&mut rng)).unwrap()
            } else {
                let out = Vector3::new(-0.5, 4.0, 0.1 * k as f64);
                Frame::from_parts(out.into(), Rotation3::identity())
            };
            // The whole search in one slice, as `solve_global` runs it without a closed form.
            let mut search = chain
                .global_search(&target, &chain.mid_range(), &ik, k)
                .unwrap();
            let whole = chain.finish_search(&mut search, ik.global_iterations, &mut || {});
            for slice in [1, 30, 45, 120] {
                let mut search = chain
                    .global_search(&target, &chain.mid_range(), &ik, k)
                    .unwrap();
                let mut answer = None;
                let mut slices = 0;
                while answer.is_none() {
                    let mut steps = 0u16;
                    answer = chain.continue_search_counted(&mut search, slice, &mut || steps += 1);
                    assert!(steps <= slice.max(ATTEMPT_ITERATIONS), "{steps} > {slice}");
                    slices += 1;
                    assert!(slices <= 400, "no end");
                }
                assert_eq!(answer, Some(whole), "target {k}, slice {slice}");
                reached += usize::from(whole.is_converged());
            }
        }
        assert!(reached > 40, "{reached} reached");
    }
}
