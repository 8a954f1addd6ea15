//! The shipped robot files, for the unit tests that run over every robot.
#![allow(clippy::unwrap_used)]

use armgate_core::config::{ValidRobot, load_file};

/// Every robot file in robots/, loaded, in name order.
pub fn robots() -> Vec<ValidRobot> {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../robots");
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    files.iter().map(|p| load_file(p).unwrap()).collect()
}
