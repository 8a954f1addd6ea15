//! The Cartesian workspace: bounds and exclusion boxes (spec §5.2).

use heapless::Vec;

use crate::config::{MAX_BOXES, WorkspaceConfig};
use crate::math::Vector3;

/// Where the tool origin may be: inside the bounds (inclusive) and not strictly inside any
/// exclusion box. Only the position is checked; the orientation is free.
#[derive(Clone, Debug)]
pub struct Workspace {
    bounds: [f64; 6],
    boxes: Vec<[f64; 6], MAX_BOXES>,
}

impl Workspace {
    /// The workspace of a robot description.
    pub fn new(config: &WorkspaceConfig) -> Self {
        Self {
            bounds: config.bounds,
            boxes: config.boxes.clone(),
        }
    }

    /// True if the tool origin may be at `p`.
    pub fn allows(&self, p: &Vector3<f64>) -> bool {
        self.within_bounds(p) && !self.boxes.iter().any(|bx| strictly_inside(bx, p))
    }

    /// How far `p` may move in any direction and stay allowed: its distance to the nearest face
    /// of the bounds or exclusion box (0 if not allowed; never NaN).
    pub fn margin(&self, p: &Vector3<f64>) -> f64 {
        if !self.allows(p) {
            return 0.0;
        }
        let [x0, x1, y0, y1, z0, z1] = self.bounds;
        let inside = [p.x - x0, x1 - p.x, p.y - y0, y1 - p.y, p.z - z0, z1 - p.z]
            .into_iter()
            .fold(f64::INFINITY, f64::min);
        self.boxes
            .iter()
            .map(|&[x0, x1, y0, y1, z0, z1]| {
                let gap = |v: f64, lo: f64, hi: f64| (lo - v).max(v - hi).max(0.0);
                let (dx, dy, dz) = (gap(p.x, x0, x1), gap(p.y, y0, y1), gap(p.z, z0, z1));
                crate::math::sqrt(dx * dx + dy * dy + dz * dz)
            })
            .fold(inside, f64::min)
    }

    /// Where the segment from `a` to `b` first enters an exclusion box (strictly inside), as
    /// a fraction 0..=1 of the way; `None` if it never does. (The bounds need no such check:
    /// a segment between two points inside a box stays inside it.)
    pub fn first_box_crossing(&self, a: &Vector3<f64>, b: &Vector3<f64>) -> Option<f64> {
        self.boxes
            .iter()
            .filter_map(|bx| segment_enters(bx, a, b))
            .reduce(f64::min)
    }

    /// Where the segment from `a` to `b` first comes within `clearance` (m, ≥ 0) of an
    /// exclusion box that does not hold `origin` (a motion that starts inside a box may drive
    /// out of it, never into another), as a fraction 0..=1 of the way: it enters the box grown
    /// by `clearance` on every side. `None` if it never does.
    pub fn first_new_box_near(
        &self,
        a: &Vector3<f64>,
        b: &Vector3<f64>,
        origin: &Vector3<f64>,
        clearance: f64,
    ) -> Option<f64> {
        self.boxes
            .iter()
            .filter(|bx| !strictly_inside(bx, origin))
            .filter_map(|bx| segment_enters(&grown(bx, clearance), a, b))
            .reduce(f64::min)
    }

    /// True if `p` lies within the bounds (inclusive), boxes aside.
    pub fn within_bounds(&self, p: &Vector3<f64>) -> bool {
        self.within_bounds_by(p, 0.0)
    }

    /// True if `p` lies at least `inset` (m) inside the bounds (inclusive).
    pub fn within_bounds_by(&self, p: &Vector3<f64>, inset: f64) -> bool {
        let [x0, x1, y0, y1, z0, z1] = grown(&self.bounds, -inset);
        x0 <= p.x && p.x <= x1 && y0 <= p.y && p.y <= y1 && z0 <= p.z && p.z <= z1
    }
}

/// The box `bx` grown by `by` on every side (shrunk for a negative `by`).
fn grown(&[x0, x1, y0, y1, z0, z1]: &[f64; 6], by: f64) -> [f64; 6] {
    [x0 - by, x1 + by, y0 - by, y1 + by, z0 - by, z1 + by]
}

/// True if `p` lies strictly inside the open box `bx`.
fn strictly_inside(&[x0, x1, y0, y1, z0, z1]: &[f64; 6], p: &Vector3<f64>) -> bool {
    x0 < p.x && p.x < x1 && y0 < p.y && p.y < y1 && z0 < p.z && p.z < z1
}

/// The fraction of the way from `a` to `b` at which the segment enters the open box `bx`
/// (slab method), if it does.
fn segment_enters(
    &[x0, x1, y0, y1, z0, z1]: &[f64; 6],
    a: &Vector3<f64>,
    b: &Vector3<f64>,
) -> Option<f64> {
    let (mut enter, mut leave) = (0.0f64, 1.0f64);
    let axes = [(a.x, b.x, x0, x1), (a.y, b.y, y0, y1), (a.z, b.z, z0, z1)];
    for (from, to, lo, hi) in axes {
        let d = to - from;
        if d == 0.0 {
            if !(lo < from && from < hi) {
                return None;
            }
            continue;
        }
        let (t0, t1) = ((lo - from) / d, (hi - from) / d);
        enter = enter.max(t0.min(t1));
        leave = leave.min(t0.max(t1));
    }
    // Open box: touching a face or an edge is not entering.
    (enter < leave).then_some(enter)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segments_enter_open_boxes_only_through_their_inside() {
        let unit = [0.0, 1.0, 0.0, 1.0, 0.0, 1.0];
        let p = |x, y, z| Vector3::new(x, y, z);
        let t = segment_enters(&unit, &p(-1.0, 0.5, 0.5), &p(3.0, 0.5, 0.5));
        assert_eq!(t, Some(0.25));
        // Along a face, past a corner, short of the box, reversed.
        assert_eq!(
            segment_enters(&unit, &p(-1.0, 0.0, 0.5), &p(2.0, 0.0, 0.5)),
            None
        );
        assert_eq!(
            segment_enters(&unit, &p(-1.0, 1.0, 0.0), &p(1.0, -1.0, 0.0)),
            None
        );
        assert_eq!(
            segment_enters(&unit, &p(-2.0, 0.5, 0.5), &p(-1.0, 0.5, 0.5)),
            None
        );
        let t = segment_enters(&unit, &p(2.0, 0.9, 0.1), &p(0.5, 0.9, 0.1));
        assert!(t.is_some_and(|t| (t - 2.0 / 3.0).abs() < 1e-12), "{t:?}");
    }
}
