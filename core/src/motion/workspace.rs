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
        let [x0, x1, y0, y1, z0, z1] = self.bounds;
        let within = x0 <= p.x && p.x <= x1 && y0 <= p.y && p.y <= y1 && z0 <= p.z && p.z <= z1;
        within
            && !self.boxes.iter().any(|&[x0, x1, y0, y1, z0, z1]| {
                x0 < p.x && p.x < x1 && y0 < p.y && p.y < y1 && z0 < p.z && p.z < z1
            })
    }
}
