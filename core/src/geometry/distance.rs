//! Closest distances of segments to segments and to axis-aligned boxes.

use crate::math::{Vector3, sqrt};

/// Below this squared length a segment is a point (m²): the closed forms divide by it.
const DEGENERATE: f64 = 1e-24;
/// Below this `sin²` of their angle two segments count as parallel: the closed form's
/// denominator loses its digits there, and taking any closest pair of the lines instead errs
/// by at most `sin θ ×` their length (1e-8 m a metre).
const PARALLEL: f64 = 1e-16;

/// A straight segment from `a` to `b` (m); `a == b` is a point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Segment {
    /// One end.
    pub a: Vector3<f64>,
    /// The other end.
    pub b: Vector3<f64>,
}

impl Segment {
    /// The segment from `a` to `b`.
    pub fn new(a: Vector3<f64>, b: Vector3<f64>) -> Self {
        Self { a, b }
    }

    /// The point at `t` (0..=1) of the way from `a` to `b`.
    pub fn at(&self, t: f64) -> Vector3<f64> {
        self.a + (self.b - self.a) * t
    }
}

/// The closest distance between two segments (m): the minimum of `|p(s) − q(t)|` over both
/// parameters in 0..=1, by the clamped closed form (the unconstrained minimum of the
/// quadratic, clamped to the square's edges one parameter at a time; exact, since the
/// squared distance is convex in both).
pub fn segment_segment(p: &Segment, q: &Segment) -> f64 {
    let d1 = p.b - p.a;
    let d2 = q.b - q.a;
    let r = p.a - q.a;
    let a = d1.dot(&d1);
    let e = d2.dot(&d2);
    let f = d2.dot(&r);
    let (s, t) = if a <= DEGENERATE && e <= DEGENERATE {
        (0.0, 0.0)
    } else if a <= DEGENERATE {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(&r);
        if e <= DEGENERATE {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(&d2);
            let denom = a * e - b * b;
            // Parallel segments (denominator 0): any s; take 0 and let t decide.
            let s = if denom > PARALLEL * (a * e) {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let t = (b * s + f) / e;
            if t < 0.0 {
                ((-c / a).clamp(0.0, 1.0), 0.0)
            } else if t > 1.0 {
                (((b - c) / a).clamp(0.0, 1.0), 1.0)
            } else {
                (s, t)
            }
        }
    };
    (p.at(s) - q.at(t)).norm()
}

/// How far `v` lies outside the interval `lo..=hi` along one axis (0 inside).
fn excess(v: f64, lo: f64, hi: f64) -> f64 {
    (lo - v).max(v - hi).max(0.0)
}

/// The distance of the point `p` to the box `[x_min, x_max, y_min, y_max, z_min, z_max]`
/// (0 inside or on it).
pub fn point_box(p: &Vector3<f64>, bx: &[f64; 6]) -> f64 {
    sqrt(squared_to_box(p, bx))
}

/// The squared distance of `p` to the box (no root: the segment's pieces compare squares).
fn squared_to_box(p: &Vector3<f64>, &[x0, x1, y0, y1, z0, z1]: &[f64; 6]) -> f64 {
    let (dx, dy, dz) = (
        excess(p.x, x0, x1),
        excess(p.y, y0, y1),
        excess(p.z, z0, z1),
    );
    dx * dx + dy * dy + dz * dz
}

/// The closest distance of a segment to the box `[x_min, x_max, y_min, y_max, z_min, z_max]`
/// (m; 0 if the segment meets the box).
///
/// Along the segment, `p(t)`'s squared distance to the box is convex and piecewise quadratic:
/// its pieces break where a coordinate crosses one of the box's six planes. On each piece
/// every axis is either inside its slab (no term) or outside on a known side (a linear
/// excess), so the piece's minimum is a clamped closed form; the smallest over the (at most
/// seven) pieces is the exact distance.
pub fn segment_box(s: &Segment, bx: &[f64; 6]) -> f64 {
    let d = s.b - s.a;
    let [x0, x1, y0, y1, z0, z1] = *bx;
    let slabs = [
        (s.a.x, d.x, x0, x1),
        (s.a.y, d.y, y0, y1),
        (s.a.z, d.z, z0, z1),
    ];
    // The break points: 0, 1 and every plane crossing strictly between them.
    let mut breaks = [1.0f64; 8];
    let mut count = 1;
    if let Some(first) = breaks.first_mut() {
        *first = 0.0;
    }
    for (from, step, lo, hi) in slabs {
        if step == 0.0 {
            continue;
        }
        for plane in [lo, hi] {
            let t = (plane - from) / step;
            if t > 0.0
                && t < 1.0
                && let Some(slot) = breaks.get_mut(count)
            {
                *slot = t;
                count += 1;
            }
        }
    }
    // The last slot stays 1; sort the crossings in between (at most six, insertion sort).
    let end = count;
    if let Some(last) = breaks.get_mut(end) {
        *last = 1.0;
    }
    if let Some(inner) = breaks.get_mut(1..end) {
        insertion_sort(inner);
    }
    let mut best = f64::INFINITY;
    for k in 0..end {
        let (Some(&t0), Some(&t1)) = (breaks.get(k), breaks.get(k + 1)) else {
            break;
        };
        let mid = 0.5 * (t0 + t1);
        // f(t) = Σ (c + g t)² over the axes outside their slab on this piece.
        let (mut cg, mut gg) = (0.0, 0.0);
        for (from, step, lo, hi) in slabs {
            let v = from + step * mid;
            let (c, g) = if v < lo {
                (lo - from, -step)
            } else if v > hi {
                (from - hi, step)
            } else {
                continue;
            };
            cg += c * g;
            gg += g * g;
        }
        // `max`/`min`, not `clamp`, which would assert t0 ≤ t1 (a panic path).
        let t = if gg > 0.0 {
            (-cg / gg).max(t0).min(t1)
        } else {
            t0
        };
        best = best.min(squared_to_box(&s.at(t), bx));
    }
    sqrt(best)
}

/// Sorts a few values in place, ascending (NaN-free input; bounded by the slice's length).
/// Neighbours are swapped through a pattern, which has no bounds check to panic on.
fn insertion_sort(v: &mut [f64]) {
    for i in 1..v.len() {
        for j in (1..=i).rev() {
            match v.get_mut(j - 1..=j) {
                Some([a, b]) if *a > *b => core::mem::swap(a, b),
                _ => break,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
        Vector3::new(x, y, z)
    }

    fn seg(a: [f64; 3], b: [f64; 3]) -> Segment {
        Segment::new(v(a[0], a[1], a[2]), v(b[0], b[1], b[2]))
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-12
    }

    #[test]
    fn segment_distances_of_known_configurations() {
        // Crossing at right angles, 1 apart in z.
        let d = segment_segment(
            &seg([-1., 0., 0.], [1., 0., 0.]),
            &seg([0., -1., 1.], [0., 1., 1.]),
        );
        assert!(close(d, 1.0), "{d}");
        // Parallel, overlapping, 0.5 apart.
        let d = segment_segment(
            &seg([0., 0., 0.], [2., 0., 0.]),
            &seg([1., 0.5, 0.], [3., 0.5, 0.]),
        );
        assert!(close(d, 0.5), "{d}");
        // Collinear, end to end with a gap of 1.
        let d = segment_segment(
            &seg([0., 0., 0.], [1., 0., 0.]),
            &seg([2., 0., 0.], [3., 0., 0.]),
        );
        assert!(close(d, 1.0), "{d}");
        // Closest points at two ends: (1,0,0) and (2,1,0).
        let d = segment_segment(
            &seg([0., 0., 0.], [1., 0., 0.]),
            &seg([2., 1., 0.], [2., 3., 0.]),
        );
        assert!(close(d, 2f64.sqrt()), "{d}");
        // Two points, a point and a segment.
        let d = segment_segment(
            &seg([1., 1., 1.], [1., 1., 1.]),
            &seg([1., 1., 3.], [1., 1., 3.]),
        );
        assert!(close(d, 2.0), "{d}");
        let d = segment_segment(
            &seg([0., 3., 0.], [0., 3., 0.]),
            &seg([-1., 0., 0.], [1., 0., 0.]),
        );
        assert!(close(d, 3.0), "{d}");
        // Intersecting.
        let d = segment_segment(
            &seg([-1., -1., 0.], [1., 1., 0.]),
            &seg([-1., 1., 0.], [1., -1., 0.]),
        );
        assert!(close(d, 0.0), "{d}");
    }

    #[test]
    fn box_distances_of_known_configurations() {
        let unit = [0.0, 1.0, 0.0, 1.0, 0.0, 1.0];
        // Through the box, touching a face, along an edge at a distance.
        assert_eq!(
            segment_box(&seg([-1., 0.5, 0.5], [2., 0.5, 0.5]), &unit),
            0.0
        );
        assert_eq!(segment_box(&seg([-1., 1., 0.5], [2., 1., 0.5]), &unit), 0.0);
        let d = segment_box(&seg([-1., 2., 2.], [2., 2., 2.]), &unit);
        assert!(close(d, 2f64.sqrt()), "{d}");
        // Past a corner diagonally: closest at t = 0.5, the point (1.5, 1.5, 0.5)... to the
        // edge x = y = 1: distance √0.5.
        let d = segment_box(&seg([2., 1., 0.5], [1., 2., 0.5]), &unit);
        assert!(close(d, 0.5f64.sqrt()), "{d}");
        // A point, and a segment above the box sloping down towards it.
        let d = segment_box(&seg([0.5, 0.5, 3.], [0.5, 0.5, 3.]), &unit);
        assert!(close(d, 2.0), "{d}");
        let d = segment_box(&seg([-2., 0.5, 3.], [0.5, 0.5, 1.5]), &unit);
        assert!(close(d, 0.5), "{d}");
    }

    fn random_point(rng: &mut SplitMix64) -> Vector3<f64> {
        v(
            rng.uniform(-2., 2.),
            rng.uniform(-2., 2.),
            rng.uniform(-2., 2.),
        )
    }

    /// Segment pairs and segment–box pairs drawn at random against a brute-force sampler:
    /// the sampled minimum is never below the exact one, and exceeds it by at most the
    /// sampling step's reach.
    #[test]
    fn random_cases_agree_with_a_brute_force_sampler() {
        let mut rng = SplitMix64::new(35);
        for case in 0..300 {
            let p = Segment::new(random_point(&mut rng), random_point(&mut rng));
            // Every tenth second segment short or a point, every fifth parallel to the first.
            let mut q = Segment::new(random_point(&mut rng), random_point(&mut rng));
            if case % 10 == 0 {
                q.b = q.a + (q.b - q.a) * 1e-3 * f64::from(case % 20);
            } else if case % 5 == 0 {
                q.b = q.a + (p.b - p.a) * rng.uniform(-1., 1.);
            }
            let exact = segment_segment(&p, &q);
            let n = 100;
            let mut sampled = f64::INFINITY;
            for i in 0..=n {
                let x = p.at(f64::from(i) / f64::from(n));
                for j in 0..=n {
                    sampled = sampled.min((x - q.at(f64::from(j) / f64::from(n))).norm());
                }
            }
            let reach = ((p.b - p.a).norm() + (q.b - q.a).norm()) / f64::from(n);
            assert!(exact <= sampled + 1e-12, "case {case}: {exact} > {sampled}");
            assert!(
                sampled - exact <= reach,
                "case {case}: {exact} vs {sampled}"
            );

            let (lo, hi) = (random_point(&mut rng), random_point(&mut rng));
            let bx = [
                lo.x.min(hi.x),
                lo.x.max(hi.x),
                lo.y.min(hi.y),
                lo.y.max(hi.y),
                lo.z.min(hi.z),
                lo.z.max(hi.z),
            ];
            let exact = segment_box(&p, &bx);
            let n = 4000;
            let sampled = (0..=n)
                .map(|i| point_box(&p.at(f64::from(i) / f64::from(n)), &bx))
                .fold(f64::INFINITY, f64::min);
            let reach = (p.b - p.a).norm() / f64::from(n);
            assert!(exact <= sampled + 1e-12, "case {case}: {exact} > {sampled}");
            assert!(
                sampled - exact <= reach,
                "case {case}: {exact} vs {sampled}"
            );
        }
    }
}
