//! Capsules: a segment with a radius, the shape of each link of the arm's envelope.

use super::distance::{Segment, segment_box, segment_segment};

/// The points within `radius` of a segment (m).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Capsule {
    /// The axis.
    pub segment: Segment,
    /// The radius (m, ≥ 0; 0 is the bare segment).
    pub radius: f64,
}

impl Capsule {
    /// The gap between the surfaces of two capsules (m): the distance of their axes less both
    /// radii. Zero or less means they touch or overlap (the amount is no penetration depth).
    pub fn gap_to_capsule(&self, other: &Capsule) -> f64 {
        segment_segment(&self.segment, &other.segment) - self.radius - other.radius
    }

    /// The gap between the capsule's surface and the box `[x_min, x_max, y_min, y_max,
    /// z_min, z_max]` (m); zero or less means they touch or overlap.
    pub fn gap_to_box(&self, bx: &[f64; 6]) -> f64 {
        segment_box(&self.segment, bx) - self.radius
    }

    /// How far the capsule stays inside the box `bounds` (m): the least distance of its
    /// surface to a face. Negative when it reaches out. The box being convex, the axis lies
    /// inside whenever both ends do, and the distance to each face is linear along the axis,
    /// so the ends decide.
    pub fn clearance_in(&self, &[x0, x1, y0, y1, z0, z1]: &[f64; 6]) -> f64 {
        let inside = |p: &crate::math::Vector3<f64>| {
            [p.x - x0, x1 - p.x, p.y - y0, y1 - p.y, p.z - z0, z1 - p.z]
                .into_iter()
                .fold(f64::INFINITY, f64::min)
        };
        inside(&self.segment.a).min(inside(&self.segment.b)) - self.radius
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vector3;

    fn capsule(a: [f64; 3], b: [f64; 3], radius: f64) -> Capsule {
        Capsule {
            segment: Segment::new(Vector3::from(a), Vector3::from(b)),
            radius,
        }
    }

    #[test]
    fn gaps_and_clearances_of_known_capsules() {
        let x = capsule([-1., 0., 0.], [1., 0., 0.], 0.1);
        let y = capsule([0., -1., 0.5], [0., 1., 0.5], 0.2);
        assert!((x.gap_to_capsule(&y) - 0.2).abs() < 1e-12);
        assert!((y.gap_to_capsule(&x) - 0.2).abs() < 1e-12);
        let column = [-0.2, 0.2, -0.2, 0.2, -0.1, 0.4];
        let above = capsule([0., 0., 0.6], [1., 0., 0.6], 0.05);
        assert!((above.gap_to_box(&column) - 0.15).abs() < 1e-12);
        let through = capsule([-1., 0., 0.], [1., 0., 0.], 0.05);
        assert!(through.gap_to_box(&column) < 0.0);
        let bounds = [-1.0, 1.0, -1.0, 1.0, 0.0, 2.0];
        let c = capsule([0., 0., 0.3], [0.5, 0., 1.8], 0.1);
        assert!((c.clearance_in(&bounds) - 0.1).abs() < 1e-12);
        let out = capsule([0., 0., 0.3], [1.05, 0., 1.0], 0.1);
        assert!((out.clearance_in(&bounds) + 0.15).abs() < 1e-12);
    }
}
