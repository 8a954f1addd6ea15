//! Joint moves checked with a bound that cannot miss (issue 33): the chain's lever arms bound
//! how far the tool strays from the chords the check evaluates, and the check subdivides
//! until that is less than the way's distance to every box and bound.
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::approx_constant
)]

mod common;

use armgate_core::config::ValidRobot;
use armgate_core::kinematics::{Chain, Joints, Levers};
use armgate_core::math::Vector3;
use armgate_core::motion::{Controller, Mode, Refusal};
use armgate_core::rng::SplitMix64;
use armgate_protocol::client::PathPoint;

fn lerp(a: &Joints, b: &Joints, s: f64) -> Joints {
    let mut q = *a;
    for ((q, a), b) in q.iter_mut().zip(a.iter()).zip(b.iter()) {
        *q = a + s * (b - a);
    }
    q
}

fn tool(chain: &Chain, q: &Joints) -> Vector3<f64> {
    chain.forward(q).unwrap().translation.vector
}

#[test]
fn the_lever_bound_is_never_exceeded_on_any_robot() {
    let mut rng = SplitMix64::new(35);
    for (name, config) in common::all_robots() {
        let chain = Chain::new(&config);
        let levers = Levers::of(&chain);
        for _ in 0..20 {
            let (a, b) = (chain.random_joints(&mut rng), chain.random_joints(&mut rng));
            let bound = levers.bound(&a, &b);
            let start = tool(&chain, &a);
            let mut travelled = 0.0;
            let mut last = start;
            for k in 1..=400 {
                let p = tool(&chain, &lerp(&a, &b, k as f64 / 400.0));
                travelled += (p - last).norm();
                assert!((p - start).norm() <= bound + 1e-12, "{name}");
                last = p;
            }
            assert!(
                travelled <= bound * (1.0 + 1e-9),
                "{name}: {travelled} > {bound}"
            );
        }
    }
}

/// ranger-mk1 with joint 1 from −4 to +4 rad, the rest at the ready pose: the tool runs round
/// the base on a circle, and the 16 chords the check used to evaluate cut inside it.
fn long_turn() -> (Joints, Joints) {
    let from = Joints::from_slice(&[-4.0, 0.6, -0.4, 0.2, 1.8, 0.1]).unwrap();
    let mut to = from;
    to[0] = 4.0;
    (from, to)
}

fn joint_rig(config: &ValidRobot, q: &Joints) -> Controller {
    let mut ctrl = Controller::new(config);
    ctrl.step(0.0, q).unwrap();
    ctrl.set_mode(Mode::Joint).unwrap();
    ctrl
}

#[test]
fn a_box_on_the_outer_arc_between_two_old_samples_is_found() {
    let config = common::robot("ranger-mk1");
    let chain = Chain::new(&config);
    let (from, to) = long_turn();
    // Halfway between the old samples 7 and 8 the arc bulges furthest from their chord.
    let (a, b) = (
        tool(&chain, &lerp(&from, &to, 7.0 / 16.0)),
        tool(&chain, &lerp(&from, &to, 8.0 / 16.0)),
    );
    let arc = tool(&chain, &lerp(&from, &to, 7.5 / 16.0));
    let bulge = (arc - (a + b) / 2.0).norm();
    assert!(bulge > 0.015, "{bulge}");
    // A cube around the arc there, a quarter of the bulge on each side: the chord misses it.
    let h = bulge / 4.0;
    let cube = [
        arc.x - h,
        arc.x + h,
        arc.y - h,
        arc.y + h,
        arc.z - h,
        arc.z + h,
    ];
    let boxed = config
        .clone()
        .edit(|c| c.workspace.boxes.push(cube).unwrap())
        .unwrap();
    let mut ctrl = joint_rig(&boxed, &from);
    assert_eq!(ctrl.move_joints(&to, 0.0), Err(Refusal::CrossesBox(46)));
    assert!(!ctrl.is_moving());
    // Without it the same move is accepted.
    let mut ctrl = joint_rig(&config, &from);
    assert!(ctrl.move_joints(&to, 0.0).is_ok());
}

#[test]
fn a_blend_that_could_stray_into_a_box_is_refused_and_without_it_the_sequence_runs() {
    let config = common::robot("ranger-mk1");
    let chain = Chain::new(&config);
    let start = Joints::from_slice(&[1.5708, 0.6, -0.4, 0.2, 1.8, 0.1]).unwrap();
    let mut via = start;
    via[0] += 0.3;
    let mut end = via;
    end[1] += 0.2;
    // A box 3 cm beyond the via point's tool position, away from the base.
    let p = tool(&chain, &via);
    let out = Vector3::new(p.x, p.y, 0.0).normalize() * 0.03;
    let c = p + out * 2.0;
    let cube = [
        c.x - 0.03,
        c.x + 0.03,
        c.y - 0.03,
        c.y + 0.03,
        c.z - 0.03,
        c.z + 0.03,
    ];
    let boxed = config
        .edit(|c| c.workspace.boxes.push(cube).unwrap())
        .unwrap();
    let run = |tolerance: f64| {
        let mut ctrl = joint_rig(&boxed, &start);
        ctrl.set_joint_via(0, &via, 0.0).unwrap();
        ctrl.set_joint_via(1, &end, 0.0).unwrap();
        ctrl.set_joint_blend(0, Some(tolerance)).unwrap();
        ctrl.start_joint_sequence()
    };
    // Passing the via point within 0.1 rad, the tool may stray 0.1 × √(Σ lever²) ≈ 10 cm from
    // the legs: the check cannot show that it misses the box 3 cm away.
    assert!(Levers::of(&chain).per_joint_distance() * 0.1 > 0.06);
    assert!(matches!(
        run(0.1),
        Err(Refusal::NearEdge(PathPoint::Along(_)))
    ));
    // Stopping at the via point (no blend), the legs keep clear of it.
    assert_eq!(run(0.0), Ok(()));
}
