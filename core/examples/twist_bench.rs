//! Per-tick cost of `Controller::step` while a twist is streamed (`TW`), on the host.
//!
//! `cargo run --release -p armgate-core --example twist_bench`
//!
//! Every tick does FK, the Jacobian, the singular-value estimate, the damped pseudo-inverse
//! (with the null-space pull on 7–8 joints), the joint-limit braking, the acceleration ramp,
//! the workspace look-ahead (two FKs) and the limiter. The twist (1 cm/s along z, 0.02 rad/s
//! about x) is re-sent every tick and reverses every second, so the ramps run too. The last
//! row jogs ranger-mk1 through its wrist singularity, where the damping is active.
#![allow(
    clippy::approx_constant,
    missing_docs,
    clippy::unwrap_used,
    clippy::indexing_slicing
)]

use std::time::Instant;

use armgate_core::config::load_file;
use armgate_core::kinematics::Joints;
use armgate_core::math::Twist;
use armgate_core::motion::{Controller, Mode};
use armgate_core::sim::IdealArm;
use armgate_protocol::client::TwistFrame;

const TICKS: usize = 20_000;

fn main() {
    println!("| robot                        | ticks  | mean µs | median µs | p99 µs | max µs |");
    println!("|------------------------------|--------|---------|-----------|--------|--------|");
    let cases: [(&str, &str, Vec<f64>, Twist); 4] = [
        (
            "ranger-mk1",
            "ranger-mk1",
            vec![1.5708, 0.6, -0.4, 0.2, 1.8, 0.1],
            Twist::new(0.0, 0.0, 0.01, 0.02, 0.0, 0.0),
        ),
        (
            "iiwa14 (null space)",
            "iiwa14",
            vec![0.3, 0.6, 1.2, -1.2, 0.4, 0.8, 0.2],
            Twist::new(0.0, 0.0, 0.01, 0.02, 0.0, 0.0),
        ),
        (
            "ranger-mk2 (null space)",
            "ranger-mk2",
            vec![
                0.1508, -0.5897, 0.3452, -1.9859, -0.3564, 0.2665, 0.6688, 0.4256,
            ],
            Twist::new(0.0, 0.0, 0.01, 0.02, 0.0, 0.0),
        ),
        (
            "ranger-mk1 wrist singularity",
            "ranger-mk1",
            vec![1.5708, 0.6, -0.4, 0.2, 3.1416, 0.1],
            Twist::new(0.01, 0.0, 0.0, 0.0, 0.0, 0.0),
        ),
    ];
    for (label, robot, start, twist) in cases {
        let path = format!("{}/../robots/{robot}.toml", env!("CARGO_MANIFEST_DIR"));
        let config = load_file(&path).unwrap();
        let mut ctrl = Controller::new(&config);
        let mut arm = IdealArm::new(Joints::from_slice(&start).unwrap());
        let dt = config.control_period;
        let per_second = (1.0 / dt) as usize;
        ctrl.step(0.0, &arm.measured()).unwrap();
        ctrl.set_mode(Mode::Cartesian).unwrap();
        let mut times = Vec::with_capacity(TICKS);
        for k in 1..=TICKS {
            let sign = if (k / per_second).is_multiple_of(2) {
                1.0
            } else {
                -1.0
            };
            ctrl.stream_twist(twist * sign, TwistFrame::Base).unwrap();
            let measured = arm.measured();
            let t0 = Instant::now();
            let out = ctrl.step(k as f64 * dt, &measured).unwrap();
            times.push(t0.elapsed().as_secs_f64() * 1e6);
            arm.step(out.command.as_ref());
        }
        times.sort_by(f64::total_cmp);
        let at = |share: f64| times[((TICKS - 1) as f64 * share) as usize];
        println!(
            "| {label:<28} | {TICKS:>6} | {:>7.2} | {:>9.2} | {:>6.2} | {:>6.2} |",
            times.iter().sum::<f64>() / TICKS as f64,
            at(0.5),
            at(0.99),
            at(1.0),
        );
    }
}
