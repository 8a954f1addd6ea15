//! The configuration of a solution as arms are named: shoulder left or right, elbow up or
//! down, wrist flipped or not. Taken from the geometry of the joints (where the wrist centre
//! and the elbow are), not from which root a solver took, so the names mean the same on every
//! closed-form family and on every robot file however it orients its joints. The three flags
//! are the bits of `armgate_protocol::client::branch` (the names live in the clients).

use armgate_protocol::client::branch::{ELBOW, SHOULDER, WRIST};

use super::chain::{Axes, Chain};
use super::family::Family;
use super::screws::{closest_meeting, misalignment};

/// A wrist centre offset along axis 2 (m) below this is no offset (a shoulder in line with
/// the base axis).
const OFFSET: f64 = 1e-6;
/// Below this (m², or a sine) a triple product is taken as zero: the flag is at its
/// singularity and reads as the clear bit.
const FLAT: f64 = 1e-9;

impl Chain {
    /// The configuration bits of joints `q` (see `branch::SHOULDER`, `ELBOW`, `WRIST`);
    /// `None` on a chain without a six-revolute-joint closed form ([`Family::SphericalWrist`],
    /// [`Family::ThreeParallel`]) or for joints that do not fit it.
    pub fn configuration(&self, q: &[f64]) -> Option<u8> {
        let form = self.closed_form()?;
        // A 7–8 joint arm's solutions for given redundancy values, and a prismatic base's, are
        // not told apart by these three (two share all of them): their solver's roots stand.
        if !matches!(
            form.fit.family,
            Family::SphericalWrist | Family::ThreeParallel
        ) {
            return None;
        }
        let q = self.checked(q).ok()?;
        let mut axes = Axes::default();
        let flange = self.tool_and_axes(&q, &mut axes).translation.vector;
        let n = self.dof();
        let axis = |i: usize| Some((axes.origin.get(i)?, axes.z.get(i)?));
        let (p1, h1) = axis(0)?;
        let (o2, h2) = axis(1)?;
        let (oe, he) = axis(2)?;
        let (_, ha) = axis(n.checked_sub(3)?)?;
        let (om, hm) = axis(n.saturating_sub(2))?;
        let (ol, hl) = axis(n.saturating_sub(1))?;
        // The wrist centre: where the last two axes meet.
        let centre = closest_meeting(om, hm, ol, hl).map_or(flange, |(x, _)| x);
        // The shoulder: where the upper arm leaves the base axis.
        let shoulder = closest_meeting(p1, h1, o2, h2).map_or(*o2, |(x, _)| x);
        // Left: the upper arm lies left of the base axis seen towards the wrist centre (axis 1
        // up): the wrist centre's offset along axis 2 (constant on a six-joint arm: the joints
        // between turn about axes parallel to it) times its distance ahead of the plane of
        // axes 1 and 2. An arm without that offset: which side of that plane the wrist centre
        // is on.
        let to_wrist = centre - p1;
        let ahead = h2.cross(h1).dot(&to_wrist);
        let offset = h2.dot(&to_wrist);
        let side = if offset.abs() <= OFFSET {
            ahead
        } else {
            ahead * offset
        };
        // Up: the elbow lies on axis 1's side of the line from the shoulder to the wrist
        // (in the arm's plane, across the elbow axis; a parallel next axis stands for the
        // wrist, as ur5's axis 4).
        let (next_o, next_h) = axis(3)?;
        let reach = if misalignment(he, next_h) < FLAT {
            next_o
        } else {
            &centre
        } - shoulder;
        let bend = he.dot(&(oe - shoulder).cross(&reach)) * he.dot(&h1.cross(&reach));
        // Flip: the wrist's middle axis against the others' cross product (the middle joint's
        // sign, whatever its zero).
        let flip = ha.cross(hl).dot(hm);
        let bit = |set: bool, flag: u8| if set { flag } else { 0 };
        Some(bit(side < -FLAT, SHOULDER) | bit(bend < -FLAT, ELBOW) | bit(flip < -FLAT, WRIST))
    }
}
