//! The closed-form IK requests: `KG` (a joint move to a Cartesian goal on a chosen branch),
//! `KR` (the redundancy values of the next `KG`), `KS` (read one of a pose's solutions) and
//! `SQ` 5 (the present branch).

use armgate_protocol::client::banks::{BANK_2, WRITE_JOINTS as BANK_LEN};
use armgate_protocol::client::branch::{BRANCH_INDEX, NEAREST_BRANCH, NO_CLOSED_FORM, NO_SOLUTION};
use armgate_protocol::client::redundancy::{CHOSEN, Redundancy};
use armgate_protocol::client::{Command, PathPoint, Reply, VALUES};

use super::redundancy::{self, Values};
use crate::kinematics::{Branch, BranchSolution, Chain, Family, Joints};
use crate::math::{Frame, Rotation3, Vector3, dist};
use crate::motion::Refusal;

/// Why a `KG`, `KR` or `KS` is refused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum IkRequestError {
    /// A value is NaN or infinite.
    BadNumber,
    /// The index names no branch (or a branch on a robot without a closed form), a redundancy
    /// parameter the arm does not have, or a `KR` choice the client has not made.
    BadIndex,
    /// The controller refuses it (no solution: the goal is out of reach).
    Refused(Refusal),
    /// The goal has solutions within the joint limits, none on the branch asked for.
    BranchBeyondLimits,
}

/// Where a `KG` goal stands: found (its joints and branch bits), or (a chain without a closed
/// form) a pose for a global search to run, in slices across ticks.
pub(super) enum Goal {
    /// The joints and the branch they lie on.
    Found(Joints, u8),
    /// The pose to search for from the present joints, answered [`NEAREST_BRANCH`].
    Search(Frame),
}

/// The refusal of a `KG` goal out of reach.
pub(super) const OUT_OF_REACH: IkRequestError =
    IkRequestError::Refused(Refusal::Unreachable(PathPoint::Goal));

/// The pose in f0..f5 (position, roll/pitch/yaw), if finite.
fn pose(v: &[f64; VALUES]) -> Result<Frame, IkRequestError> {
    let [x, y, z, roll, pitch, yaw, _] = *v;
    if ![x, y, z, roll, pitch, yaw].iter().all(|c| c.is_finite()) {
        return Err(IkRequestError::BadNumber);
    }
    let rotation = Rotation3::from_euler_angles(roll, pitch, yaw);
    Ok(Frame::from_parts(Vector3::new(x, y, z).into(), rotation))
}

/// `KR`'s choice: the values its index names (f0 θ3, f1 θ5), each finite. Refused on a
/// chain without a redundant closed form, and θ5 on one of seven joints. (The joint limits are
/// the controller's to check.)
pub(super) fn choice(
    chain: &Chain,
    v: &[f32; VALUES],
    index: u8,
) -> Result<Values, IkRequestError> {
    let chosen = Redundancy::parse(v, index).ok_or(IkRequestError::BadIndex)?;
    let parameters = chain.redundancy_parameters().len();
    if parameters == 0 || (chosen.theta5.is_some() && parameters < 2) {
        return Err(IkRequestError::BadIndex);
    }
    let values = [chosen.theta3, chosen.theta5];
    if values.iter().flatten().any(|x| !x.is_finite()) {
        return Err(IkRequestError::BadNumber);
    }
    Ok(values.map(|x| x.map(f64::from)))
}

/// The reference of a `KG` or `KS` whose index has [`CHOSEN`]: `present` with the client's
/// `KR` choice put in (refused if it made none); `present` as it is without that bit. Also
/// whether the choice was put in.
pub(super) fn reference(
    chain: &Chain,
    mut present: Joints,
    index: u8,
    choice: Option<Values>,
) -> Result<(Joints, bool), IkRequestError> {
    if index & CHOSEN == 0 {
        return Ok((present, false));
    }
    let values = choice.ok_or(IkRequestError::BadIndex)?;
    redundancy::apply(values, chain.redundancy_parameters(), &mut present);
    Ok((present, true))
}

/// The branch bits of solution `s` on the wire: its configuration (shoulder, elbow, wrist as
/// arms name them, from the geometry; every closed-form family has one).
fn bits(chain: &Chain, s: &BranchSolution) -> u8 {
    chain.configuration(&s.q).unwrap_or(s.branch.bits())
}

/// The joints of `KG`'s goal and the branch bits they lie on, or on a robot without a closed
/// form the pose for a global IK search from the present joints ([`Goal`]). `reference`
/// is the present joints, with the client's choice of the redundancy parameters if `chosen`:
/// then the goal keeps them (no other values are tried).
pub(super) fn goal(
    chain: &Chain,
    (reference, chosen): (&Joints, bool),
    v: &[f64; VALUES],
    index: u8,
) -> Result<Goal, IkRequestError> {
    let target = pose(v)?;
    let branch = match index & !CHOSEN {
        NEAREST_BRANCH => None,
        bits => Some(
            Branch::from_bits(bits)
                .ok_or(IkRequestError::BadIndex)?
                .bits(),
        ),
    };
    if chain.family().family == Family::Numeric {
        if branch.is_some() {
            return Err(IkRequestError::BadIndex);
        }
        return Ok(Goal::Search(target));
    }
    if branch.is_some_and(|b| b & !chain.configuration_flags() != 0) {
        return Err(IkRequestError::BadIndex);
    }
    if !chosen && let Some((q, bits)) = already_there(chain, &target, reference, branch) {
        return Ok(Goal::Found(q, bits));
    }
    let solve = |root| nearest(chain, &target, (reference, chosen), root);
    let Some(wanted) = branch else {
        return solve(None)
            .map(|s| Goal::Found(s.q, bits(chain, &s)))
            .ok_or(OUT_OF_REACH);
    };
    // The solver's root branches tried for the one in the configuration asked for: one root
    // gives each configuration of a pose.
    let on_branch = (0..NEAREST_BRANCH)
        .find_map(|root| solve(Branch::from_bits(root)).filter(|s| bits(chain, s) == wanted));
    match on_branch {
        Some(found) => Ok(Goal::Found(found.q, wanted)),
        None if solve(None).is_some() => Err(IkRequestError::BranchBeyondLimits),
        None => Err(OUT_OF_REACH),
    }
}

/// The solution of `target` nearest `reference` on the solver's `root` branch (if given),
/// keeping the reference's redundancy values if `chosen`. Out of line: inlined at `goal`'s
/// three calls it cost the firmware 3 KB of flash.
#[inline(never)]
fn nearest(
    chain: &Chain,
    target: &Frame,
    (reference, chosen): (&Joints, bool),
    root: Option<Branch>,
) -> Option<BranchSolution> {
    let found = if chosen {
        chain.solve_nearest_keeping(target, reference, root)
    } else {
        chain.solve_nearest(target, reference, root)
    };
    found.ok().flatten()
}

/// How near a `KG` goal the arm may already be for the goal to be the present joints: a pose
/// on the wire is an f32 (a few 1e-7), as `armgate pose` prints it six decimals. Near a
/// singularity the exact solution of a goal that close can lie far away (hybrid at home: θ3 a
/// quarter turn, the slides 0.5 m out), which is not what a client asking for the arm's own
/// pose means.
const ALREADY_THERE: f64 = 1e-6;

/// The present joints and their branch, if they reach `target` within [`ALREADY_THERE`]
/// (m + rad) on the branch asked for.
fn already_there(
    chain: &Chain,
    target: &Frame,
    present: &Joints,
    branch: Option<u8>,
) -> Option<(Joints, u8)> {
    let pose = chain.forward(present).ok()?;
    if dist(&pose, target) > ALREADY_THERE {
        return None;
    }
    let on = present_bits(chain, present)?;
    branch.is_none_or(|b| b == on).then_some((*present, on))
}

/// The branch bits of the present joints: their configuration.
fn present_bits(chain: &Chain, present: &Joints) -> Option<u8> {
    chain.configuration(present)
}

/// `SK`: the `k`-th solution of the pose in f0..f5 (joints in f0..f5, the count in f6, the
/// branch in the index), each joint on the turn nearest `reference`. `index` is `k`, with
/// [`BANK_2`] for joints 7.. in f0.. (refused on six joints or fewer, as for `jP`); on a
/// redundant arm the solutions are those for `reference`'s values of its redundancy
/// parameters (the present ones, or the client's choice with [`CHOSEN`]).
pub(super) fn solution(
    chain: &Chain,
    reference: &Joints,
    v: &[f64; VALUES],
    index: u8,
) -> Result<Reply, IkRequestError> {
    let (k, bank_2) = (index & !(BANK_2 | CHOSEN), index & BANK_2 != 0);
    if bank_2 && chain.dof() <= BANK_LEN {
        return Err(IkRequestError::BadIndex);
    }
    let target = pose(v)?;
    let mut values = [0.0f32; VALUES];
    let Ok(solutions) = chain.solve_all(&target, reference) else {
        values[VALUES - 1] = NO_CLOSED_FORM;
        return Ok(reply(Command::IkSolution, values, NO_SOLUTION));
    };
    values[VALUES - 1] = solutions.len() as f32;
    let Some(found) = solutions.get(usize::from(k)) else {
        return Ok(reply(Command::IkSolution, values, NO_SOLUTION));
    };
    let joints = found.q.iter().skip(if bank_2 { BANK_LEN } else { 0 });
    for (o, q) in values.iter_mut().zip(joints).take(VALUES - 1) {
        *o = *q as f32;
    }
    Ok(reply(Command::IkSolution, values, bits(chain, found)))
}

/// `QS` index 5: the branch of the present joints in f0 (−1: none, or no closed form).
pub(super) fn present_branch(chain: &Chain, present: Option<&Joints>) -> Reply {
    let bits = present
        .and_then(|q| present_bits(chain, q))
        .map_or(-1.0, f32::from);
    let mut values = [0.0f32; VALUES];
    values[0] = bits;
    reply(Command::Status, values, BRANCH_INDEX)
}

fn reply(command: Command, values: [f32; VALUES], index: u8) -> Reply {
    Reply {
        command,
        values,
        index,
    }
}
