//! What keeping the replay reservation costs on a computer: one `StateFile::keep` (the value
//! written whole to a temporary file, synced, renamed over the old one), and how often a
//! controller in use writes one.
//!
//! `cargo run --release -p armgate-core --example state_file_bench [DIR]`
//!
//! DIR (default: the system's temporary directory) should be on the disk the state file will
//! live on: the sync is most of the cost. Prints the mean, the slowest and the writes an hour
//! of continuous signed use needs (one per `RESERVE_AHEAD` of the clients' clocks at most).
#![allow(missing_docs, clippy::unwrap_used)]

use std::time::Instant;

use armgate_core::cycle::{RESERVE_AHEAD, ReplayStore, StateFile};
use armgate_protocol::client::signed::TIMESTAMP_UNIT_US;

const WRITES: u32 = 200;

fn main() {
    let dir = std::env::args()
        .nth(1)
        .map_or_else(std::env::temp_dir, Into::into);
    let path = dir.join(format!("armgate-state-bench-{}", std::process::id()));
    let mut file = StateFile::open(&path).unwrap();
    let mut slowest = 0f64;
    let started = Instant::now();
    for k in 0..WRITES {
        let one = Instant::now();
        assert!(
            file.keep(1_000_000 + u64::from(k)),
            "{:?}",
            file.take_error()
        );
        slowest = slowest.max(one.elapsed().as_secs_f64());
    }
    let mean = started.elapsed().as_secs_f64() / f64::from(WRITES);
    let _ = std::fs::remove_file(&path);
    let interval_s = (RESERVE_AHEAD * TIMESTAMP_UNIT_US) as f64 * 1e-6;
    println!(
        "state file in {}: {WRITES} writes, mean {:.3} ms, slowest {:.3} ms; at most one per {interval_s} s of signed use ({:.0} an hour)",
        dir.display(),
        mean * 1e3,
        slowest * 1e3,
        3600.0 / interval_s
    );
}
