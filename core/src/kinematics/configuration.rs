//! The configuration of a solution as arms are named: shoulder left or right, elbow up or
//! down, wrist flipped or not. Taken from the geometry of the joints (where the wrist centre
//! and the elbow are), not from which root a solver took, so the names mean the same on every
//! closed-form family and on every robot file however it orients its joints. The three flags
//! are the bits of `armgate_protocol::client::branch` (the names live in the clients).

use armgate_protocol::client::branch::{ELBOW, SHOULDER, WRIST};

use super::chain::{Axes, Chain};
use super::family::Family;
use super::screws::closest_meeting;

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
        self.tool_and_axes(&q, &mut axes);
        // Both families have six joints: the wrist is axes 4 to 6.
        let axis = |i: usize| Some((axes.origin.get(i)?, axes.z.get(i)?));
        let (p1, h1) = axis(0)?;
        let (o2, h2) = axis(1)?;
        let (oe, he) = axis(2)?;
        let (o4, ha) = axis(3)?;
        let (om, hm) = axis(4)?;
        let (ol, hl) = axis(5)?;
        // The wrist centre: where the last two axes meet.
        let (centre, _) = closest_meeting(om, hm, ol, hl)?;
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
        // (in the arm's plane, across the elbow axis; three parallel axes: axis 4 stands for
        // the wrist). Axis 2 is parallel to the elbow's, so any point of it is the shoulder.
        let wrist = if form.fit.family == Family::ThreeParallel {
            o4
        } else {
            &centre
        };
        let reach = wrist - o2;
        let bend = he.dot(&(oe - o2).cross(&reach)) * he.dot(&h1.cross(&reach));
        // Flip: the wrist's middle axis against the others' cross product (the middle joint's
        // sign, whatever its zero).
        let flip = ha.cross(hl).dot(hm);
        let bit = |set: bool, flag: u8| if set { flag } else { 0 };
        Some(bit(side < -FLAT, SHOULDER) | bit(bend < -FLAT, ELBOW) | bit(flip < -FLAT, WRIST))
    }
}
