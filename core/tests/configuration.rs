//! Configurations named as arms are named (shoulder left/right, elbow up/down, wrist flip or
//! not), computed from the geometry of the joints: known values on puma560, ur5 and
//! ranger-mk1, and every solution of a pose in a configuration of its own on every closed-form
//! robot.
#![allow(missing_docs, clippy::unwrap_used, clippy::indexing_slicing)]

mod common;

use armgate_core::kinematics::{Chain, Family};
use armgate_core::rng::SplitMix64;
use armgate_protocol::client::branch::{ELBOW, SHOULDER, WRIST};

fn chain(name: &str) -> Chain {
    Chain::new(&common::robot(name))
}

/// Left, up, no flip: every bit clear.
const LUN: u8 = 0;

#[test]
fn known_configurations_of_puma560() {
    let puma = chain("puma560");
    // Upper arm raised 0.7 rad, forearm folded 2 rad: the elbow above the line from the
    // shoulder to the wrist centre, which lies ahead (+x) with the upper arm offset to +y, the
    // left seen from behind the arm; θ5 > 0.
    let q = [0.0, -0.7, 2.0, 0.3, 0.6, 0.1];
    assert_eq!(puma.configuration(&q), Some(LUN));
    // θ5 < 0: the wrist flipped.
    assert_eq!(
        puma.configuration(&[0.0, -0.7, 2.0, 0.3, -0.6, 0.1]),
        Some(WRIST)
    );
    // AKB's zero ("L-shaped": upper arm horizontal, forearm up): the elbow below the line.
    assert_eq!(
        puma.configuration(&[0.0, 0.0, 0.0, 0.0, 0.5, 0.0]),
        Some(ELBOW)
    );
    // The same pose's other root of θ1 (about 2.74 rad away) reaches the wrist centre from
    // behind, the upper arm on the other side: shoulder right, and only there.
    for s in puma.solve_all(&puma.forward(&q).unwrap(), &q).unwrap() {
        let right = s.q[0].abs() > 1.0;
        let bits = puma.configuration(&s.q).unwrap();
        assert_eq!(bits & SHOULDER != 0, right, "{s:?}");
    }
    // The classic eight: the first random pose that all eight reach within the limits, one in
    // each configuration.
    let mut rng = SplitMix64::new(560);
    let all = (0..100)
        .map(|_| {
            let q = puma.random_joints(&mut rng);
            puma.solve_all(&puma.forward(&q).unwrap(), &q).unwrap()
        })
        .find(|all| all.len() == 8)
        .unwrap();
    let mut seen: Vec<u8> = all
        .iter()
        .map(|s| puma.configuration(&s.q).unwrap())
        .collect();
    seen.sort_unstable();
    assert_eq!(seen, (0..8).collect::<Vec<u8>>(), "{all:?}");
}

#[test]
fn known_configurations_of_ur5_and_ranger_mk1() {
    let ur5 = chain("ur5");
    // The elbow above the line from the shoulder to axis 4; θ5 > 0.
    assert_eq!(
        ur5.configuration(&[0.0, -0.7, 2.0, 0.3, 0.6, 0.1]),
        Some(LUN)
    );
    assert_eq!(
        ur5.configuration(&[0.0, -0.7, 2.0, 0.3, -0.6, 0.1]),
        Some(WRIST)
    );
    // Elbow bent the other way: below the line.
    assert_eq!(
        ur5.configuration(&[0.0, -0.7, -1.0, 0.3, 0.6, 0.1]),
        Some(ELBOW)
    );
    let ranger = chain("ranger-mk1");
    let home = common::robot("ranger-mk1").home();
    let at_home = ranger.configuration(&home[..]).unwrap();
    // From home, bending joint 3 the other way crosses the stretched elbow: up and down swap.
    let mut bent = home;
    bent[2] = -bent[2];
    let other = ranger.configuration(&bent[..]).unwrap();
    assert_eq!(at_home ^ other, ELBOW, "{home:?}");
}

#[test]
fn every_solution_of_a_pose_has_a_configuration_of_its_own() {
    for name in ["puma560", "ur5", "ranger-mk1"] {
        let chain = chain(name);
        assert_ne!(chain.family().family, Family::Numeric);
        let mut rng = SplitMix64::new(37);
        let mut eights = 0;
        for _ in 0..200 {
            let q = chain.random_joints(&mut rng);
            let pose = chain.forward(&q).unwrap();
            let all = chain.solve_all(&pose, &q).unwrap();
            let mut seen: Vec<u8> = all
                .iter()
                .map(|s| chain.configuration(&s.q).unwrap())
                .collect();
            // The configuration of the joints the pose came from is among them.
            assert!(
                seen.contains(&chain.configuration(&q).unwrap()),
                "{name} {q:?}"
            );
            seen.sort_unstable();
            seen.dedup();
            assert_eq!(seen.len(), all.len(), "{name} {q:?}: {all:?}");
            eights += usize::from(all.len() == 8);
        }
        println!("{name}: {eights} of 200 poses with all 8 solutions");
    }
    // A 7–8 joint arm's solutions for given redundancy values, and a prismatic base's, include
    // some in the same geometric configuration: they report the solver's roots
    // (docs/kinematics.md).
    for name in ["iiwa14", "ranger-mk2", "hybrid"] {
        assert_eq!(
            chain(name).configuration(&chain(name).mid_range()[..]),
            None
        );
    }
}
