//! What recording costs the control loop: the time of one `Tap::record` call (a `try_send` of
//! an event by value into the bounded queue) while the recorder thread translates and writes
//! an MCAP file, for the events of one tick (joints plus CAN frames). Prints figures; asserts
//! nothing.
//!
//! `cargo run --release -p armgate-viz --example record_bench`

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use std::time::Instant;

use armgate_core::config::load_file;
use armgate_core::kinematics::{Chain, Joints};
use armgate_core::math::Frame;
use armgate_protocol::can::CanFrame;
use armgate_viz::mcap_file::McapFile;
use armgate_viz::recorder::{Recorder, Sink};
use armgate_viz::translate::Event;

fn main() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../robots/ur5.toml");
    let robot = load_file(std::path::Path::new(path)).unwrap();
    let chain = Chain::new(&robot);
    let file = std::env::temp_dir().join(format!("record-bench-{}.mcap", std::process::id()));
    let sinks: Vec<Box<dyn Sink>> =
        vec![Box::new(McapFile::create(&file, &robot, "bench").unwrap())];
    let recorder = Recorder::start(&robot, 0.0, sinks).unwrap();
    let tap = recorder.tap();
    let period = robot.control_period;
    let frame = CanFrame::new(0x181, &[1, 2, 3, 4, 5, 6, 7, 8]).unwrap();
    let ticks = 2000;
    let mut calls = Vec::with_capacity(ticks * 13);
    let q: Joints = chain.mid_range();
    let pose: Frame = chain.forward(&q).unwrap();
    let started = Instant::now();
    for k in 0..ticks {
        let t = k as f64 * period;
        // One tick of ur5 on the simulated bus: twelve frames and the joints.
        for _ in 0..12 {
            let at = Instant::now();
            tap.record(Event::Can { t, frame });
            calls.push(at.elapsed().as_nanos() as u64);
        }
        let at = Instant::now();
        tap.record(Event::Joints {
            t,
            measured: q,
            command: Some(q),
            setpoint: None,
            pose: Some(pose),
        });
        calls.push(at.elapsed().as_nanos() as u64);
        // Paced like the simulator (real time), so the recorder thread keeps up or drops.
        let due = started + std::time::Duration::from_secs_f64(t + period);
        if let Some(wait) = due.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
    }
    let dropped = tap.dropped();
    let (written, _) = recorder.finish().unwrap();
    calls.sort_unstable();
    let pct = |p: f64| calls[((calls.len() - 1) as f64 * p) as usize];
    let mean = calls.iter().sum::<u64>() as f64 / calls.len() as f64;
    println!(
        "ur5, {ticks} ticks at {:.2} ms, {} record() calls: mean {mean:.0} ns, median {} ns, p99 {} ns, max {} ns",
        period * 1e3,
        calls.len(),
        pct(0.5),
        pct(0.99),
        pct(1.0),
    );
    let size = std::fs::metadata(&file).map(|m| m.len()).unwrap_or(0);
    println!(
        "{written} messages written, {dropped} events dropped, file {:.1} MB",
        size as f64 / 1e6
    );
    let _ = std::fs::remove_file(&file);
}
