//! Which closed-form family a chain belongs to, detected from its geometry when the chain is
//! built (so at validation time), and the ideal model of that family nearest to it.
//!
//! The test is on the joint axes at the zero configuration ([`Screws`]), not on DH numbers, so
//! it does not matter how the file spells the geometry (rounded twists such as 1.5708, offsets,
//! base and tool frames). A chain within [`EXACT`] of the family is solved in closed form
//! directly; one within [`NEAR`] (a calibrated arm: β ≠ 0, fitted twists and lengths) is solved
//! on its ideal model and every solution polished by Newton steps on the true chain.

use nalgebra::Vector3;

use super::chain::Chain;
use super::screws::{Screws, closest_meeting, distance_to_line, misalignment};
use super::subproblems::{Circle, Elbow, Mirror, Sinusoid, TANGENT};

/// Deviation (m, or the sine of an angle) up to which the chain is the family's ideal model.
const EXACT: f64 = 1e-9;
/// Deviation up to which the chain is solved on its ideal model and polished.
const NEAR: f64 = 1e-2;
/// The subproblems' slack beyond a tangency on an ideal model ([`ClosedForm::slack`]).
const NEAR_SLACK: f64 = 0.05;
/// Two axes at least this far from parallel (sine) count as distinct directions.
const DISTINCT: f64 = 0.1;

/// The closed-form families of revolute arms.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    /// Axes 2 and 3 parallel, axes 4, 5 and 6 meeting in one point (the wrist centre); any
    /// offsets elsewhere (ranger-mk1, puma560). Up to 8 solutions.
    SphericalWrist,
    /// Axes 2, 3 and 4 parallel, axes 5 and 6 meeting (ur5). Up to 8 solutions.
    ThreeParallel,
    /// Seven or eight joints: axes 1–3 meeting in the shoulder, axes 5 to the last meeting in
    /// the wrist centre, axis 4 (the elbow) through neither (iiwa14, ranger-mk2). Redundant:
    /// θ3, and θ5 on eight joints, are parameters taken from the reference. Up to 8 solutions
    /// for each value.
    SphericalShoulder,
    /// Six joints: two prismatic joints along distinct directions (a base sliding in a plane),
    /// then four revolute joints whose middle two axes, 4 and 5, are parallel (hybrid: base
    /// yaw, two pitches, roll). Up to 4 solutions.
    PrismaticBase,
    /// No closed form here (other prismatic joints, not six joints, or other geometry): the
    /// numeric solver only.
    Numeric,
}

/// The family of a chain and how closely the chain fits it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FamilyFit {
    /// The family.
    pub family: Family,
    /// The largest distance (m) or sine of an angle by which the chain misses the family's
    /// ideal model: 0 up to rounding for a nominal robot file, small for a calibrated one.
    pub deviation: f64,
}

impl FamilyFit {
    /// True if the chain is solved in closed form without Newton polishing.
    pub fn is_exact(&self) -> bool {
        self.family != Family::Numeric && self.deviation <= EXACT
    }
}

/// A detected family: the ideal model the closed form solves and the point it is built on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct ClosedForm {
    pub fit: FamilyFit,
    /// The ideal model: the chain's screws with the family's conditions made exact.
    pub screws: Screws,
    /// Where the last axes meet: the wrist centre, or the point on axes 5 and 6; for a
    /// prismatic base, axis 4's point, about which θ4 swings axis 5.
    pub centre: Vector3<f64>,
    /// What every solve of a six-joint revolute family shares.
    pub fixed: Option<Fixed>,
}

/// The parts of a six-joint revolute family's solve that depend on the ideal model only,
/// taken once when the family is detected (each solve took them again, with two `atan2`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Fixed {
    /// θ3 from the distance between axis 2's point and the wrist centre (for three parallel
    /// axes, axis 4's point).
    pub elbow: Elbow,
    /// The wrist's second root from its first, if its middle axis is perpendicular to the
    /// others (axes 4, 5, 6; for three parallel axes, 2, 5, 6).
    pub mirror: Option<Mirror>,
    /// Three parallel axes: θ5 from `h2ᵀ R5 h6`, and the circle of the planar part
    /// `R(h2, Σ) (c − o4)`.
    pub parallel: Option<(Sinusoid, Circle)>,
}

impl Fixed {
    /// The parts of `form`'s family; `None` for the other families. Out of line: inlined into
    /// the chain's construction, it cost the firmware 3 KB of flash.
    #[inline(never)]
    fn of(form: &ClosedForm) -> Option<Self> {
        let [_, h2, h3, h4, h5, h6, _, _] = &form.screws.axis;
        let [_, o2, o3, o4, _, _, _, _] = &form.screws.point;
        let c = &form.centre;
        match form.fit.family {
            Family::SphericalWrist => Some(Self {
                elbow: Elbow::new(h3, c - o3, o2 - o3),
                mirror: Mirror::of(h4, h5, h6),
                parallel: None,
            }),
            Family::ThreeParallel => Some(Self {
                elbow: Elbow::new(h3, o4 - o3, o2 - o3),
                mirror: Mirror::of(h2, h5, h6),
                parallel: Some((Sinusoid::new(h2, h5, h6), Circle::new(h2, &(c - o4)))),
            }),
            _ => None,
        }
    }
}

impl ClosedForm {
    /// How far beyond a tangency the subproblems accept data: rounding for an exact model;
    /// for an ideal model of a calibrated arm, enough that a target the true arm reaches at the
    /// edge of its workspace still gives the ideal model's tangent root, which Newton polishes.
    pub fn slack(&self) -> f64 {
        if self.fit.is_exact() {
            TANGENT
        } else {
            NEAR_SLACK
        }
    }

    /// The family `chain` belongs to, if any.
    pub fn detect(chain: &Chain) -> Option<Self> {
        let dof = chain.dof();
        let screws = Screws::of(chain);
        if (0..dof).any(|i| chain.is_prismatic(i)) {
            let base = dof == 6
                && chain.is_prismatic(0)
                && chain.is_prismatic(1)
                && !(2..dof).any(|i| chain.is_prismatic(i));
            return if base { prismatic_base(&screws) } else { None };
        }
        let form = match dof {
            6 => spherical_wrist(&screws).or_else(|| three_parallel(&screws)),
            7 | 8 => spherical_shoulder(&screws, dof),
            _ => None,
        }?;
        Some(Self {
            fixed: Fixed::of(&form),
            ..form
        })
    }
}

/// Axes `first..=last` made parallel to `axis[first]` (each keeps its sense); the largest
/// misalignment. `None` if any is not nearly parallel.
fn make_parallel(screws: &mut Screws, first: usize, last: usize) -> Option<f64> {
    let h = *screws.axis.get(first)?;
    let mut worst = 0.0f64;
    for axis in screws.axis.iter_mut().take(last + 1).skip(first + 1) {
        let sin = misalignment(&h, axis);
        if sin > NEAR {
            return None;
        }
        worst = worst.max(sin);
        *axis = if h.dot(axis) >= 0.0 { h } else { -h };
    }
    Some(worst)
}

/// Axes `a` and `b` meet (within [`NEAR`]): their meeting point and the gap.
fn meeting(screws: &Screws, a: usize, b: usize) -> Option<(Vector3<f64>, f64)> {
    let (pa, ha) = (screws.point.get(a)?, screws.axis.get(a)?);
    let (pb, hb) = (screws.point.get(b)?, screws.axis.get(b)?);
    if misalignment(ha, hb) < DISTINCT {
        return None;
    }
    closest_meeting(pa, ha, pb, hb).filter(|(_, gap)| *gap <= NEAR)
}

/// Every axis from `first` to `last` moved (parallel to itself) through `centre`.
fn through(screws: &mut Screws, first: usize, last: usize, centre: &Vector3<f64>) {
    for point in screws.point.iter_mut().take(last + 1).skip(first) {
        *point = *centre;
    }
}

fn distinct(screws: &Screws, a: usize, b: usize) -> bool {
    match (screws.axis.get(a), screws.axis.get(b)) {
        (Some(x), Some(y)) => misalignment(x, y) >= DISTINCT,
        _ => false,
    }
}

fn fit(family: Family, deviation: f64, screws: Screws, centre: Vector3<f64>) -> Option<ClosedForm> {
    (deviation <= NEAR).then_some(ClosedForm {
        fit: FamilyFit { family, deviation },
        screws,
        centre,
        fixed: None,
    })
}

/// Axes 2 ∥ 3, axes 4, 5, 6 through one point.
fn spherical_wrist(chain: &Screws) -> Option<ClosedForm> {
    if !distinct(chain, 0, 1) {
        return None;
    }
    let mut ideal = *chain;
    let parallel = make_parallel(&mut ideal, 1, 2)?;
    let (centre, gap) = meeting(chain, 3, 4)?;
    if !distinct(chain, 4, 5) {
        return None;
    }
    let off = distance_to_line(&centre, &chain.point[5], &chain.axis[5]);
    through(&mut ideal, 3, 5, &centre);
    fit(
        Family::SphericalWrist,
        parallel.max(gap).max(off),
        ideal,
        centre,
    )
}

/// Axes 2 ∥ 3 ∥ 4, axes 5 and 6 meeting, axis 5 not parallel to the others.
fn three_parallel(chain: &Screws) -> Option<ClosedForm> {
    if !distinct(chain, 0, 1) || !distinct(chain, 1, 4) {
        return None;
    }
    let mut ideal = *chain;
    let parallel = make_parallel(&mut ideal, 1, 3)?;
    let (centre, gap) = meeting(chain, 4, 5)?;
    through(&mut ideal, 4, 5, &centre);
    fit(Family::ThreeParallel, parallel.max(gap), ideal, centre)
}

/// Axes 1–3 through one point (the shoulder), axes 5 to `dof` through another (the wrist), the
/// elbow's axis 4 through neither (else θ4 could not set the distance between them).
fn spherical_shoulder(chain: &Screws, dof: usize) -> Option<ClosedForm> {
    // The wrist's solved joints are its last three; the first of them meets the next.
    let wrist_first = dof.checked_sub(3)?;
    if !distinct(chain, 0, 1)
        || !distinct(chain, wrist_first, wrist_first + 1)
        || !distinct(chain, wrist_first + 1, wrist_first + 2)
    {
        return None;
    }
    let (shoulder, shoulder_gap) = meeting(chain, 0, 1)?;
    let (wrist, wrist_gap) = meeting(chain, wrist_first, wrist_first + 1)?;
    let off = |x: &Vector3<f64>, i: usize| match (chain.point.get(i), chain.axis.get(i)) {
        (Some(p), Some(h)) => distance_to_line(x, p, h),
        _ => f64::INFINITY,
    };
    if off(&shoulder, 3) <= NEAR || off(&wrist, 3) <= NEAR {
        return None;
    }
    let mut deviation = shoulder_gap.max(wrist_gap).max(off(&shoulder, 2));
    for i in 4..dof {
        deviation = deviation.max(off(&wrist, i));
    }
    let mut ideal = *chain;
    through(&mut ideal, 0, 2, &shoulder);
    through(&mut ideal, 4, dof - 1, &wrist);
    fit(Family::SphericalShoulder, deviation, ideal, wrist)
}

/// Slides 1 and 2 along distinct directions, axes 4 ∥ 5 and apart (else θ4 could not set the
/// height), axis 3 ∦ 4 and axis 6 ∦ 5 (else θ3, θ4 + θ5 and θ6 could not make every rotation).
/// Only the parallel pair is made exact in the ideal model: nothing else needs to be.
fn prismatic_base(chain: &Screws) -> Option<ClosedForm> {
    if !distinct(chain, 0, 1) || !distinct(chain, 2, 3) || !distinct(chain, 4, 5) {
        return None;
    }
    let pivot = chain.point[3];
    if distance_to_line(&chain.point[4], &pivot, &chain.axis[3]) <= NEAR {
        return None;
    }
    let mut ideal = *chain;
    let parallel = make_parallel(&mut ideal, 3, 4)?;
    fit(Family::PrismaticBase, parallel, ideal, pivot)
}
