//! See the arm: a URDF of any robot file whose frames are armgate's forward kinematics, and
//! recordings of a running controller in MCAP (Foxglove's JSON schemas), made off the control
//! loop by a recorder thread, and served live over the Foxglove WebSocket protocol. `armgate urdf` runs this crate's `armgate-viz` tool; `armgate-sim
//! --mcap` records with it. See docs/visualisation.md.

pub mod body;
pub mod body_scene;
pub mod clearance_plot;
pub mod foxglove;
pub mod live;
pub mod mcap_file;
pub mod recorder;
pub mod translate;
pub mod urdf;

#[cfg(test)]
mod test_robots;
