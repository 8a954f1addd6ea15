//! Shared helpers of the core's integration tests.
#![allow(
    dead_code,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]

pub mod arm_rig;
pub mod clients;
pub mod experiments;

use std::path::PathBuf;

use armgate_core::config::{IkConfig, ValidRobot, load_file};
use armgate_core::kinematics::{Chain, IkResult};
use armgate_core::math::Frame;

/// The workspace's `robots/` folder.
pub fn robots_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../robots")
}

/// Loads `robots/<name>.toml`.
pub fn robot(name: &str) -> ValidRobot {
    let path = robots_dir().join(format!("{name}.toml"));
    load_file(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Every shipped robot file, by name.
pub fn all_robots() -> Vec<(String, ValidRobot)> {
    let mut names: Vec<_> = std::fs::read_dir(robots_dir())
        .unwrap()
        .filter_map(|e| {
            let p = e.unwrap().path();
            (p.extension()? == "toml")
                .then(|| p.file_stem().unwrap().to_string_lossy().into_owned())
        })
        .collect();
    names.sort();
    names.into_iter().map(|n| (n.clone(), robot(&n))).collect()
}

/// Global IK from the middle of the ranges reaches `target` within the limits without a
/// Newton step: the closed form's answer.
pub fn assert_global_ik_exact(chain: &Chain, ik: &IkConfig, target: &Frame, k: u64, what: &str) {
    let result = chain
        .solve_global(target, &chain.mid_range(), ik, k)
        .unwrap();
    let IkResult::Converged(found) = result else {
        panic!("{what}: {result:?}");
    };
    assert!(chain.within_limits(&found.q), "{what}");
    assert_eq!(found.iterations, 0, "{what}: closed form, no Newton step");
}

/// A request datagram: two characters, seven floats, the index.
pub fn datagram(cmd: &str, values: [f32; 7], index: u8) -> [u8; 31] {
    let mut d = [0u8; 31];
    d[..2].copy_from_slice(cmd.as_bytes());
    for (k, v) in values.iter().enumerate() {
        d[2 + 4 * k..6 + 4 * k].copy_from_slice(&v.to_le_bytes());
    }
    d[30] = index;
    d
}

/// A reply's seven floats.
pub fn floats(reply: &[u8; 31]) -> [f32; 7] {
    core::array::from_fn(|k| f32::from_le_bytes(reply[2 + 4 * k..6 + 4 * k].try_into().unwrap()))
}
