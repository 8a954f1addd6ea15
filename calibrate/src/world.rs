//! Writing a world `[base]`: the instrument's frame becomes the robot file's world frame.
//!
//! The controller checks the workspace in the frame of its Cartesian poses: the robot file's
//! world frame (the base frame {0} when the file has no `[base]`). A calibrated file whose
//! `[base]` places the robot in the instrument's frame moves that frame, so its workspace must
//! move with it, or every box would guard a different place. Workspace regions are axis-aligned
//! boxes, and a turned box is not one: when the turn is not a quarter-turn multiple, an
//! exclusion box becomes the axis-aligned box around the carried one (it guards at least the
//! same space) and the bounds become the centred axis-aligned box of largest volume inside the
//! carried bounds (they allow no more than before).

use armgate_core::config::WorkspaceConfig;
use nalgebra::{Isometry3, Matrix3, Point3, Vector3};

/// Rotation entries within this of −1, 0 or 1 make a turn that maps axes onto axes.
const AXIS_ALIGNED: f64 = 1e-9;

/// A workspace carried into another frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Carried {
    /// The workspace in the new frame.
    pub workspace: WorkspaceConfig,
    /// True if the boxes are exactly the old ones; false if enlarged (exclusion boxes) or
    /// shrunk (bounds) to stay axis-aligned.
    pub exact: bool,
}

/// `workspace`, stated in a frame whose coordinates `to_new` maps to the new frame's, stated
/// in the new frame (exactly, or conservatively: see the module).
pub fn carry(workspace: &WorkspaceConfig, to_new: &Isometry3<f64>) -> Carried {
    let r = to_new.rotation.to_rotation_matrix().into_inner();
    let abs = r.abs();
    let exact = r.iter().all(|v| {
        [-1.0, 0.0, 1.0]
            .iter()
            .any(|k| (v - k).abs() < AXIS_ALIGNED)
    });
    let mut carried = workspace.clone();
    carried.bounds = inscribed(&workspace.bounds, to_new, &abs);
    for b in carried.boxes.iter_mut() {
        *b = enclosing(b, to_new, &abs);
    }
    Carried {
        workspace: carried,
        exact,
    }
}

/// Centre and half extents of `[x_min, x_max, y_min, y_max, z_min, z_max]`.
fn centre_half(b: &[f64; 6]) -> (Vector3<f64>, Vector3<f64>) {
    let [x0, x1, y0, y1, z0, z1] = *b;
    (
        Vector3::new(x0 + x1, y0 + y1, z0 + z1) / 2.0,
        Vector3::new(x1 - x0, y1 - y0, z1 - z0) / 2.0,
    )
}

/// The box of centre `c` and half extents `h`.
fn from_centre_half(c: Vector3<f64>, h: Vector3<f64>) -> [f64; 6] {
    [
        c.x - h.x,
        c.x + h.x,
        c.y - h.y,
        c.y + h.y,
        c.z - h.z,
        c.z + h.z,
    ]
}

/// The axis-aligned box around `b` carried by `t` (`abs`: its rotation's absolute entries).
fn enclosing(b: &[f64; 6], t: &Isometry3<f64>, abs: &Matrix3<f64>) -> [f64; 6] {
    let (c, h) = centre_half(b);
    from_centre_half(t.transform_point(&Point3::from(c)).coords, abs * h)
}

/// The centred axis-aligned box of largest volume inside `b` carried by `t`: half extents `e`
/// with `|R|ᵀe ≤ h` (every corner inside), found by a log-barrier Newton method (three
/// unknowns), then scaled until a constraint is tight (exact for a quarter turn).
fn inscribed(b: &[f64; 6], t: &Isometry3<f64>, abs: &Matrix3<f64>) -> [f64; 6] {
    let (c, h) = centre_half(b);
    let a = abs.transpose();
    let centre = t.transform_point(&Point3::from(c)).coords;
    // Strictly inside to start: the enclosing box's proportions, scaled well in.
    let around = abs * h;
    let mut e = around * (0.5 * fit_scale(&a, &h, &around));
    if !(e.iter().all(|v| *v > 0.0)) {
        return from_centre_half(centre, Vector3::zeros());
    }
    // maximise  τ·Σ ln eⱼ + Σ ln sᵢ,  sᵢ = hᵢ − (A e)ᵢ,  for growing τ.
    let objective = |e: &Vector3<f64>, tau: f64| {
        let s = h - a * e;
        if e.iter().chain(s.iter()).any(|v| *v <= 0.0) {
            return f64::NEG_INFINITY;
        }
        tau * e.iter().map(|v| v.ln()).sum::<f64>() + s.iter().map(|v| v.ln()).sum::<f64>()
    };
    let mut tau = 1.0;
    for _ in 0..8 {
        for _ in 0..30 {
            let s = h - a * e;
            let inv_s = s.map(|v| 1.0 / v);
            let gradient = e.map(|v| tau / v) - a.transpose() * inv_s;
            let hessian = -Matrix3::from_diagonal(&e.map(|v| tau / (v * v)))
                - a.transpose() * Matrix3::from_diagonal(&inv_s.component_mul(&inv_s)) * a;
            let Some(step) = hessian.try_inverse().map(|inv| -(inv * gradient)) else {
                break;
            };
            let now = objective(&e, tau);
            let mut length = 1.0;
            while length > 1e-12 && objective(&(e + step * length), tau) < now {
                length /= 2.0;
            }
            let next = e + step * length;
            let done = (next - e).norm() <= 1e-15 * e.norm().max(1.0);
            if objective(&next, tau) >= now {
                e = next;
            }
            if done {
                break;
            }
        }
        tau *= 10.0;
    }
    from_centre_half(centre, e * fit_scale(&a, &h, &e))
}

/// The largest `s` with `A (s·e) ≤ h`.
fn fit_scale(a: &Matrix3<f64>, h: &Vector3<f64>, e: &Vector3<f64>) -> f64 {
    let reach = a * e;
    h.iter()
        .zip(reach.iter())
        .filter(|(_, r)| **r > 0.0)
        .map(|(h, r)| h / r)
        .fold(f64::INFINITY, f64::min)
}
