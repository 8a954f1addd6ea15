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
        let result = self.solve_global_counted(target, seed, config, rng_seed, &mut || {})?;
        Ok(self.finished(target, result, config.tolerance))
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

    /// [`solve_global`](Self::solve_global), calling `on_step` once per Newton step taken, so a
    /// test can count the budget spent independently of the reported `iterations`.
    fn solve_global_counted(
        &self,
        target: &Frame,
        seed: &[f64],
        config: &IkConfig,
        rng_seed: u64,
        on_step: &mut impl FnMut(),
    ) -> Result<IkResult, IkError> {
        let mut start = [0.0; MAX_JOINTS];
        self.prepare(target, seed, &mut start)?;
        let mut q = start;
        let mut rng = SplitMix64::new(rng_seed);
        let mut budget = config.global_iterations;
        let mut best: Option<IkSolution> = None;
        let mut used = 0u32;
        let mut last = LastEvaluation::default();
        // Each attempt spends at least one iteration, so this bound is never the binding one.
        for _ in 0..config.global_iterations {
            let limit = budget.min(ATTEMPT_ITERATIONS);
            let descent = self.descend(
                target,
                q,
                limit,
                config.tolerance,
                (Bounds::Wrapping, &mut last),
                on_step,
            );
            used += descent.steps;
            // The steps actually taken (at most `limit`), not the index of the best pose: the
            // budget bounds the work. An attempt takes at least one step unless it converged.
            let spent = u16::try_from(descent.steps).unwrap_or(u16::MAX).max(1);
            budget = budget.saturating_sub(spent);
            let mut found = descent.best;
            found.iterations = used;
            if descent.converged {
                return Ok(IkResult::Converged(found));
            }
            if best.is_none_or(|b| score(&found) < score(&b)) {
                best = Some(found);
            }
            if budget == 0 {
                break;
            }
            q = self.random_configuration(&mut rng);
        }
        // Only a zero budget leaves no attempt: then the answer is the (clamped) seed itself.
        let mut best = best.unwrap_or_else(|| {
            self.descend(
                target,
                start,
                0,
                config.tolerance,
                (Bounds::Wrapping, &mut last),
                on_step,
            )
            .best
        });
        best.iterations = used;
        Ok(IkResult::NotConverged(best))
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
                let result = chain
                    .solve_global_counted(
                        &target,
                        &chain.mid_range(),
                        &ik,
                        u64::from(k),
                        &mut || steps += 1,
                    )
                    .unwrap();
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
            let result = chain
                .solve_global_counted(&target, &chain.mid_range(), &ik, k, &mut || steps += 1)
                .unwrap();
            assert_eq!(result.solution().iterations, steps);
            assert!(steps <= u32::from(ik.global_iterations));
        }
    }
}
