//! Per-tick cost of `Controller::step` in Cartesian mode, on the host.
//!
//! `cargo run --release -p armgate-core --example step_bench`
//!
//! The arm runs a circle (R = 0.05 m, T = 4 s, x–z plane) through the IK with an ideal arm, so
//! every tick does FK, the shape generator, the workspace check, tracking IK and the limiter.
#![allow(
    clippy::approx_constant,
    missing_docs,
    clippy::unwrap_used,
    clippy::indexing_slicing
)]

use std::time::Instant;

use armgate_core::config::load_file;
use armgate_core::kinematics::Joints;
use armgate_core::motion::{Controller, Mode, Shape};
use armgate_core::sim::IdealArm;

const TICKS: usize = 20_000;

fn main() {
    println!("| robot      | ticks  | mean µs | median µs | p99 µs | max µs |");
    println!("|------------|--------|---------|-----------|--------|--------|");
    for (name, start) in [
        ("ranger-mk1", vec![1.5708, 0.6, -0.4, 0.2, 1.8, 0.1]),
        // The E9 rectangle's first corner: well conditioned, the circle stays reachable.
        (
            "ranger-mk2",
            vec![
                0.1508, -0.5897, 0.3452, -1.9859, -0.3564, 0.2665, 0.6688, 0.4256,
            ],
        ),
    ] {
        let path = format!("{}/../robots/{name}.toml", env!("CARGO_MANIFEST_DIR"));
        let config = load_file(&path)
            .unwrap()
            .edit(|config| {
                for j in config.joints.iter_mut() {
                    j.max_rate = 10.0;
                    j.drive.max_speed = 10.0;
                }
            })
            .unwrap();
        let mut ctrl = Controller::new(&config);
        let mut arm = IdealArm::new(Joints::from_slice(&start).unwrap());
        let dt = config.control_period;
        ctrl.step(0.0, &arm.measured()).unwrap();
        ctrl.set_mode(Mode::Cartesian).unwrap();
        ctrl.start_shape(Shape::Circle {
            radius: 0.05,
            period: 4.0,
            axis_i: 0,
            axis_j: 2,
        })
        .unwrap();
        let mut times = Vec::with_capacity(TICKS);
        let mut diverged = 0;
        for k in 1..=TICKS {
            let measured = arm.measured();
            let t0 = Instant::now();
            let out = ctrl.step(k as f64 * dt, &measured).unwrap();
            times.push(t0.elapsed().as_secs_f64() * 1e6);
            diverged += usize::from(out.events.ik_divergence);
            arm.step(out.command.as_ref());
        }
        times.sort_by(f64::total_cmp);
        let mean = times.iter().sum::<f64>() / TICKS as f64;
        println!(
            "| {name:<10} | {TICKS:>6} | {mean:>7.2} | {:>9.2} | {:>6.2} | {:>6.2} |{}",
            times[TICKS / 2],
            times[TICKS * 99 / 100],
            times[TICKS - 1],
            if diverged > 0 {
                format!(" ({diverged} diverged ticks)")
            } else {
                String::new()
            }
        );
    }
}
