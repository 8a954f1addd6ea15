//! The configuration of a solution as arms are named: shoulder left or right, elbow up or
//! down, wrist flipped or not. Taken from the geometry of the joints (where the wrist centre
//! and the elbow are), not from which root a solver took, so the names mean the same on every
//! closed-form family and on every robot file however it orients its joints. The three flags
//! are the bits of `armgate_protocol::client::branch` (the names live in the clients).
//!
//! Each family's flags are the ones its solver's two-way choices change, so the solutions of
//! one pose (for given redundancy values on a 7–8 joint arm) have a configuration each:
//! * six revolute joints: the wrist centre's side of the shoulder, the elbow above or below
//!   the line from the shoulder to the wrist, the wrist's middle joint's sign;
//! * a spherical shoulder (7–8 joints): the wrist centre ahead of or behind the plane of axes
//!   1 and 2, the elbow's bend about axis 4, the wrist's middle joint's sign (KUKA's status
//!   bits, A2, A4, A6 < 0, where the elbow is straight; at a fixed θ3 the sign of A2 does not
//!   tell the two shoulder solutions apart, this side does);
//! * a prismatic base: the roll axis's side of the plane of the yaw and the first pitch axis
//!   (shoulder), the elbow's side of the normal of the slides' plane through the first pitch
//!   axis; it has no wrist of three axes, so the wrist flag never applies.

use armgate_protocol::client::branch::{ELBOW, SHOULDER, WRIST};
use nalgebra::Vector3;

use super::chain::{Axes, Chain};
use super::family::Family;
use super::screws::closest_meeting;

/// A wrist centre offset along axis 2 (m) below this is no offset (a shoulder in line with
/// the base axis).
const OFFSET: f64 = 1e-6;
/// Below this (m², or a sine) a triple product is taken as zero: the flag is at its
/// singularity and reads as the clear bit.
const FLAT: f64 = 1e-9;

/// The flags from the three signed measures (negative: set).
fn bits(shoulder: f64, elbow: f64, wrist: f64) -> u8 {
    let bit = |x: f64, flag: u8| if x < -FLAT { flag } else { 0 };
    bit(shoulder, SHOULDER) | bit(elbow, ELBOW) | bit(wrist, WRIST)
}

/// The sign of the middle of three axes against the others' cross product: a wrist's flip.
fn flip(first: &Vector3<f64>, middle: &Vector3<f64>, last: &Vector3<f64>) -> f64 {
    first.cross(last).dot(middle)
}

impl Chain {
    /// The configuration bits that can be set on this chain: all three, but the wrist's on a
    /// prismatic base (it has no wrist of three axes); none without a closed form.
    pub fn configuration_flags(&self) -> u8 {
        match self.closed_form().map(|form| form.fit.family) {
            Some(Family::PrismaticBase) => SHOULDER | ELBOW,
            Some(Family::Numeric) | None => 0,
            Some(_) => SHOULDER | ELBOW | WRIST,
        }
    }

    /// The configuration bits of joints `q` (see `branch::SHOULDER`, `ELBOW`, `WRIST`);
    /// `None` on a chain without a closed form or for joints that do not fit it.
    pub fn configuration(&self, q: &[f64]) -> Option<u8> {
        let family = self.closed_form()?.fit.family;
        let q = self.checked(q).ok()?;
        let mut axes = Axes::default();
        self.tool_and_axes(&q, &mut axes);
        let axis = |i: usize| Some((axes.origin.get(i)?, axes.z.get(i)?));
        let (p1, h1) = axis(0)?;
        let (o2, h2) = axis(1)?;
        let (o3, h3) = axis(2)?;
        let (o4, h4) = axis(3)?;
        if family == Family::PrismaticBase {
            let (o5, _) = axis(4)?;
            let (_, h6) = axis(5)?;
            // The orientation's two roots (θ3, θ4 + θ5): the roll axis against the yaw's and
            // the pitch's, as a wrist's flip; θ4's two roots: the elbow (axis 5) on either
            // side of the slides' plane's normal through axis 4.
            let side = h4.dot(&h1.cross(h2).cross(&(o5 - o4)));
            return Some(bits(flip(h3, h4, h6), side, 0.0));
        }
        // The wrist: the last three axes (4–6, 5–7, 6–8), the last two meeting in its centre.
        let last = self.dof().checked_sub(1)?;
        let (_, hw) = axis(last.checked_sub(2)?)?;
        let (om, hm) = axis(last - 1)?;
        let (ol, hl) = axis(last)?;
        let (centre, _) = closest_meeting(om, hm, ol, hl)?;
        let wrist = flip(hw, hm, hl);
        match family {
            Family::SphericalWrist | Family::ThreeParallel => {
                // Left: the upper arm lies left of the base axis seen towards the wrist centre
                // (axis 1 up): the wrist centre's offset along axis 2 (constant on a six-joint
                // arm: the joints between turn about axes parallel to it) times its distance
                // ahead of the plane of axes 1 and 2. An arm without that offset: which side of
                // that plane the wrist centre is on.
                let to_wrist = centre - p1;
                let ahead = h2.cross(h1).dot(&to_wrist);
                let offset = h2.dot(&to_wrist);
                let side = if offset.abs() <= OFFSET {
                    ahead
                } else {
                    ahead * offset
                };
                // Up: the elbow lies on axis 1's side of the line from the shoulder to the
                // wrist (in the arm's plane, across the elbow axis; three parallel axes: axis 4
                // stands for the wrist). Axis 2 is parallel to the elbow's, so any point of it
                // is the shoulder.
                let reach = if family == Family::ThreeParallel {
                    o4 - o2
                } else {
                    centre - o2
                };
                let bend = h3.dot(&(o3 - o2).cross(&reach)) * h3.dot(&h1.cross(&reach));
                Some(bits(side, bend, wrist))
            }
            Family::SphericalShoulder => {
                let (shoulder, _) = closest_meeting(p1, h1, o2, h2)?;
                // Ahead: the wrist centre's side of the plane of axes 1 and 2 (which of
                // subproblem 2's roots θ1, θ2 took); bend: its side of the plane of axis 4
                // and the shoulder (which of subproblem 3's roots θ4 took), set for A4 < 0 on
                // the iiwa as KUKA's status bit.
                let ahead = h2.cross(h1).dot(&(centre - shoulder));
                let bend = h4.dot(&(centre - o4).cross(&(shoulder - o4)));
                Some(bits(ahead, bend, wrist))
            }
            Family::PrismaticBase | Family::Numeric => None,
        }
    }
}
