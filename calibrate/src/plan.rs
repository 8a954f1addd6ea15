//! Pose planning: which joint configurations to measure so that the parameters are well
//! determined.
//!
//! Candidates are drawn uniformly within the joint limits (fixed seed) and kept if the nominal
//! tool position lies in the robot's workspace and the whole arm is clear of the exclusion boxes,
//! the bounds and itself (the controller refuses a joint move to any other pose). From them, N poses are chosen greedily to
//! maximise `det(JᵀJ)` of the scaled identification Jacobian — equivalently the observability
//! index O1 = (σ₁…σ_m)^(1/m) / √N (Borm and Menq) — each step adding the candidate with the
//! largest `det(I + B M⁻¹ Bᵀ)`, where B is its 3-row block and M the information so far; then
//! exchange passes swap a chosen pose for a candidate while that raises the determinant.

use armgate_core::config::ValidRobot;
use armgate_core::kinematics::Chain;
use armgate_core::motion::{Body, Workspace};
use armgate_core::rng::SplitMix64;
use nalgebra::DMatrix;

use crate::identify::{self, Identifiability};
use crate::model::{FitSet, Geometry, MeasuredIn};

/// Draws before giving up, per pose wanted (a robot whose workspace excludes nearly every
/// configuration is misconfigured).
const DRAWS_PER_POSE: usize = 1000;
/// Prior information `ε·I`: makes the first greedy steps well-defined; negligible after.
const PRIOR: f64 = 1e-6;

/// Why no plan could be made.
#[derive(Clone, Debug, PartialEq)]
pub enum PlanError {
    /// Too few random configurations put the tool inside the workspace, the arm clear.
    Unreachable {
        /// Configurations found.
        found: usize,
        /// Configurations wanted.
        wanted: usize,
    },
}

impl std::fmt::Display for PlanError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Unreachable { found, wanted } => write!(
                f,
                "only {found} of {wanted} random configurations put the tool inside the workspace \
                 and the arm clear of the boxes and itself"
            ),
        }
    }
}

impl std::error::Error for PlanError {}

/// `count` random joint configurations within the limits whose nominal tool position the
/// workspace allows, from generator `seed` (simulated measurements, checks).
pub fn random_poses(
    config: &ValidRobot,
    count: usize,
    seed: u64,
) -> Result<Vec<Vec<f64>>, PlanError> {
    draw_poses(config, count, seed, None)
}

/// The same, keeping only those where the whole arm is clear of the exclusion boxes, the bounds
/// and itself: the poses a measuring run can be sent to.
pub fn reachable_poses(
    config: &ValidRobot,
    count: usize,
    seed: u64,
) -> Result<Vec<Vec<f64>>, PlanError> {
    draw_poses(config, count, seed, Some(&Body::new(config)))
}

fn draw_poses(
    config: &ValidRobot,
    count: usize,
    seed: u64,
    body: Option<&Body>,
) -> Result<Vec<Vec<f64>>, PlanError> {
    let chain = Chain::new(config);
    let workspace = Workspace::new(&config.workspace);
    let mut rng = SplitMix64::new(seed);
    let mut poses = Vec::with_capacity(count);
    for _ in 0..count.saturating_mul(DRAWS_PER_POSE) {
        if poses.len() == count {
            break;
        }
        let q = chain.random_joints(&mut rng);
        if chain
            .forward(&q)
            .is_ok_and(|tool| workspace.allows(&tool.translation.vector))
            && body.is_none_or(|body| body.present_at(&chain, &q).is_empty())
        {
            poses.push(q.to_vec());
        }
    }
    if poses.len() < count {
        return Err(PlanError::Unreachable {
            found: poses.len(),
            wanted: count,
        });
    }
    Ok(poses)
}

/// A proposed set of poses to measure.
#[derive(Clone, Debug)]
pub struct Plan {
    /// Joint configurations, in the order chosen (the most informative first).
    pub poses: Vec<Vec<f64>>,
    /// The identifiability of the parameters at these poses (condition number, O1).
    pub analysis: Identifiability,
    /// How many candidates the poses were chosen from.
    pub candidates: usize,
}

/// Chooses `count` poses out of `candidates` random ones (seeded) that best determine the
/// parameters of `set` — and, measured in an instrument's frame, that frame's six.
pub fn plan(
    config: &ValidRobot,
    set: FitSet,
    measured_in: MeasuredIn,
    count: usize,
    candidates: usize,
    seed: u64,
) -> Result<Plan, PlanError> {
    let pool = reachable_poses(config, candidates.max(count), seed)?;
    let geometry = Geometry::new(config);
    let all = identify::analyse(&geometry, &geometry.candidates(set, measured_in), &pool);
    let params = &all.identified;
    let j = identify::scaled(
        &identify::jacobian(&geometry, params, &pool),
        params,
        all.reach,
    );
    let chosen = d_optimal(&j, count);
    let poses: Vec<Vec<f64>> = chosen
        .iter()
        .filter_map(|&k| pool.get(k).cloned())
        .collect();
    let analysis = identify::analyse(&geometry, &geometry.candidates(set, measured_in), &poses);
    Ok(Plan {
        poses,
        analysis,
        candidates: pool.len(),
    })
}

/// How often the exchange sweeps over the chosen poses at most.
const EXCHANGE_PASSES: usize = 3;

/// Indices of `count` 3-row blocks of `j` with a large `det(JᵀJ)`: chosen greedily, then
/// improved by exchanges.
fn d_optimal(j: &DMatrix<f64>, count: usize) -> Vec<usize> {
    let m = j.ncols();
    let blocks = j.nrows() / 3;
    let block = |k: usize| j.rows(3 * k, 3);
    // The gain of adding block b to information whose inverse is `inverse`:
    // det(M + BᵀB) / det(M) = det(I + B M⁻¹ Bᵀ).
    let gain = |k: usize, inverse: &DMatrix<f64>| {
        let b = block(k);
        (DMatrix::<f64>::identity(3, 3) + b * inverse * b.transpose()).determinant()
    };
    let best_free = |free: &[bool], inverse: &DMatrix<f64>| {
        free.iter()
            .enumerate()
            .filter(|(_, f)| **f)
            .map(|(k, _)| (k, gain(k, inverse)))
            .fold(None, |best: Option<(usize, f64)>, (k, g)| match best {
                Some((_, bg)) if bg >= g => best,
                _ => Some((k, g)),
            })
    };
    let mut information = DMatrix::<f64>::identity(m, m) * PRIOR;
    let mut chosen = Vec::with_capacity(count);
    let mut free = vec![true; blocks];
    for _ in 0..count.min(blocks) {
        let Some(inverse) = information.clone().try_inverse() else {
            break;
        };
        let Some((k, _)) = best_free(&free, &inverse) else {
            break;
        };
        information += block(k).transpose() * block(k);
        if let Some(f) = free.get_mut(k) {
            *f = false;
        }
        chosen.push(k);
    }
    // Exchange: replace a chosen pose by a free one while that raises det(JᵀJ).
    for _ in 0..EXCHANGE_PASSES {
        let mut improved = false;
        for slot in 0..chosen.len() {
            let Some(&k) = chosen.get(slot) else { break };
            let without = &information - block(k).transpose() * block(k);
            let Some(inverse) = without.clone().try_inverse() else {
                continue;
            };
            let keep = gain(k, &inverse);
            let Some((c, g)) = best_free(&free, &inverse) else {
                break;
            };
            if g > keep * (1.0 + 1e-9) {
                information = without + block(c).transpose() * block(c);
                if let (Some(out), Some(into)) = (free.get_mut(k), chosen.get_mut(slot)) {
                    *out = true;
                    *into = c;
                }
                if let Some(f) = free.get_mut(c) {
                    *f = false;
                }
                improved = true;
            }
        }
        if !improved {
            break;
        }
    }
    chosen
}
