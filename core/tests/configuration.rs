//! Configurations named as arms are named (shoulder left/right, elbow up/down, wrist flip or
//! not), computed from the geometry of the joints: known values on every robot, every
//! solution of a pose in a configuration of its own, and a configuration's name solved back
//! to its pose (issue 37).
#![allow(missing_docs, clippy::unwrap_used, clippy::indexing_slicing)]

mod common;

use armgate_core::kinematics::{Branch, Chain, Family};
use armgate_core::math::dist;
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

/// Every robot file with a closed form.
const ROBOTS: [&str; 6] = [
    "puma560",
    "ur5",
    "ranger-mk1",
    "iiwa14",
    "ranger-mk2",
    "hybrid",
];

#[test]
fn known_configurations_of_iiwa14_are_kukas_status_bits() {
    // KUKA's status: A2 < 0, A4 < 0, A6 < 0 (the elbow straight: the shoulder's side is then
    // A2's sign).
    let iiwa = chain("iiwa14");
    let q = |a2: f64, a4: f64, a6: f64| [0.3, a2, 0.0, a4, 0.2, a6, 0.1];
    assert_eq!(iiwa.configuration(&q(0.5, 0.0, 0.7)), Some(LUN));
    assert_eq!(iiwa.configuration(&q(-0.5, 0.0, 0.7)), Some(SHOULDER));
    assert_eq!(iiwa.configuration(&q(0.5, -1.0, 0.7)), Some(ELBOW));
    assert_eq!(iiwa.configuration(&q(0.5, 1.0, -0.7)), Some(WRIST));
    assert_eq!(
        iiwa.configuration(&q(-0.5, -1.0, -0.7)),
        Some(SHOULDER | ELBOW | WRIST)
    );
    // At θ3 = 0 a bent elbow moves the wrist centre: A2 = 0.2 with A4 = 1.2 leans it behind
    // the plane of axes 1 and 2, and the shoulder bit follows the wrist centre, not A2.
    assert_eq!(iiwa.configuration(&q(0.2, 1.2, 0.7)), Some(SHOULDER));
    // Straight up: every flag at its singularity, clear.
    assert_eq!(iiwa.configuration(&[0.0; 7]), Some(LUN));
}

#[test]
fn known_configurations_of_ranger_mk2_and_hybrid() {
    let mk2 = chain("ranger-mk2");
    // Joint 4's offset (a4 = 0.1524 m): the elbow's bend changes sign away from θ4 = 0.
    let q = |a2: f64, a4: f64, a7: f64| [0.0, a2, 0.0, a4, 0.0, 0.0, a7, 0.0];
    assert_eq!(mk2.configuration(&q(0.5, 1.0, 0.5)), Some(LUN));
    assert_eq!(mk2.configuration(&q(0.5, 1.0, -0.5)), Some(WRIST));
    assert_eq!(
        mk2.configuration(&q(0.5, -1.0, 0.5)),
        Some(SHOULDER | ELBOW)
    );
    assert_eq!(mk2.configuration(&q(0.5, 0.0, 0.5)), Some(ELBOW));
    // hybrid: the shoulder is the sign of θ4 + θ5 (the roll axis's lean), the elbow the link
    // from axis 4 to axis 5 against the vertical (the slides' plane's normal); at home the
    // link is horizontal (elbow down) and the roll axis in line with the yaw's (clear).
    let hybrid = chain("hybrid");
    assert_eq!(hybrid.configuration(&[0.0; 6]), Some(ELBOW));
    assert_eq!(
        hybrid.configuration(&[0.1, -0.2, 0.3, 0.5, 0.3, 0.1]),
        Some(SHOULDER | ELBOW)
    );
    // θ4 = 2 turns that link past the vertical: elbow up.
    assert_eq!(
        hybrid.configuration(&[0.1, -0.2, 0.3, 2.0, -1.0, 0.1]),
        Some(SHOULDER)
    );
    assert_eq!(
        hybrid.configuration(&[0.0, 0.0, 0.0, 0.5, -0.8, 0.0]),
        Some(ELBOW)
    );
    // No wrist of three axes: its flag is never set, nor accepted (command tests).
    assert_eq!(hybrid.configuration_flags(), SHOULDER | ELBOW);
    assert_eq!(mk2.configuration_flags(), SHOULDER | ELBOW | WRIST);
}

#[test]
fn every_solution_of_a_pose_has_a_configuration_of_its_own() {
    for name in ROBOTS {
        let chain = chain(name);
        assert_ne!(chain.family().family, Family::Numeric);
        let mut rng = SplitMix64::new(37);
        let mut fulls = 0;
        for _ in 0..200 {
            let q = chain.random_joints(&mut rng);
            let pose = chain.forward(&q).unwrap();
            // On a redundant arm: the solutions for q's own redundancy values.
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
            assert!(
                seen.iter().all(|b| b & !chain.configuration_flags() == 0),
                "{name}: {seen:?}"
            );
            seen.sort_unstable();
            seen.dedup();
            assert_eq!(seen.len(), all.len(), "{name} {q:?}: {all:?}");
            fulls += usize::from(all.len() == 1 << chain.configuration_flags().count_ones());
        }
        println!("{name}: {fulls} of 200 poses with every configuration");
    }
}

/// Name → solve → FK: for random poses (seeded, per robot), each configuration the pose has is
/// found again by its name alone, as `KG` finds it (the solver's roots tried for the one in
/// that configuration), from another reference, and reaches the same pose.
#[test]
fn a_configuration_named_solves_back_to_its_pose() {
    for name in ROBOTS {
        let chain = chain(name);
        let mut rng = SplitMix64::new(3_700 + name.len() as u64);
        let mut checked = 0;
        for _ in 0..60 {
            let q = chain.random_joints(&mut rng);
            let pose = chain.forward(&q).unwrap();
            let reference = chain.random_joints(&mut rng);
            // The redundancy values kept at q's, so the names are those of q's solutions.
            let mut reference = reference.to_vec();
            for &p in chain.redundancy_parameters() {
                reference[p] = q[p];
            }
            for s in chain.solve_all(&pose, &q).unwrap() {
                let wanted = chain.configuration(&s.q).unwrap();
                let found = (0..8)
                    .filter_map(|root| {
                        chain
                            .solve_nearest_keeping(
                                &pose,
                                &reference,
                                Some(Branch::from_bits(root).unwrap()),
                            )
                            .unwrap()
                    })
                    .find(|f| chain.configuration(&f.q) == Some(wanted))
                    .unwrap_or_else(|| panic!("{name}: {wanted} of {q:?}"));
                let reached = chain.forward(&found.q).unwrap();
                assert!(dist(&reached, &pose) < 1e-8, "{name} {wanted}: {found:?}");
                checked += 1;
            }
        }
        println!("{name}: {checked} configurations solved back");
    }
}
