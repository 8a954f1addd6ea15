//! See the arm: a URDF of any robot file whose frames are armgate's forward kinematics, and
//! (in later modules) MCAP recordings and a live Foxglove view of a running controller.
//! `armgate urdf` runs this crate's `armgate-viz` tool. See docs/visualisation.md.

pub mod urdf;
