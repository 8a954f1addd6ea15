//! The arm's body (`config::Envelope`): its frames agree with the chain's, every shipped robot
//! has one and starts clear of everything, a home pose in collision is refused with the link
//! and the obstacle named, and the sweep bound holds for every point of every capsule.
#![allow(clippy::unwrap_used, clippy::indexing_slicing)]

mod common;

use armgate_core::MAX_JOINTS;
use armgate_core::config::{ConfigReason, Envelope, MAX_CAPSULES, Placed, RobotConfig, frames_at};
use armgate_core::geometry::Capsule;
use armgate_core::kinematics::Chain;
use armgate_core::math::Frame;
use armgate_core::rng::SplitMix64;
use armgate_protocol::client::{Hit, Obstacle};
use common::{all_robots, robot};

fn placed(config: &RobotConfig, q: &[f64]) -> (Envelope, Placed) {
    let envelope = Envelope::new(config);
    let placed = place(&envelope, config, q);
    (envelope, placed)
}

fn place(envelope: &Envelope, config: &RobotConfig, q: &[f64]) -> Placed {
    let mut placed = [Capsule::default(); MAX_CAPSULES];
    envelope.place(&frames_at(config, q), &mut placed);
    placed
}

#[test]
fn validation_frames_agree_with_the_chain() {
    let mut rng = SplitMix64::new(7);
    for (name, robot) in all_robots() {
        let chain = Chain::new(&robot);
        for _ in 0..50 {
            let q = chain.random_joints(&mut rng);
            let frames = frames_at(&robot, &q);
            let mut links = [Frame::identity(); MAX_JOINTS];
            let tool = chain.link_frames(&q, &mut links).unwrap();
            let n = robot.dof();
            let close = |a: &Frame, b: &Frame| {
                (a.translation.vector - b.translation.vector).norm() < 1e-12
                    && (a.rotation.matrix() - b.rotation.matrix()).norm() < 1e-12
            };
            assert!(close(&frames[0], chain.base()), "{name}");
            for i in 0..n {
                assert!(close(&frames[i + 1], &links[i]), "{name} frame {}", i + 1);
            }
            assert!(close(&frames[n + 1], &tool), "{name} tool");
        }
    }
}

#[test]
fn every_shipped_robot_has_a_body_and_starts_clear() {
    for (name, robot) in all_robots() {
        let (envelope, placed) = placed(&robot, &robot.home());
        assert!(envelope.len() >= 3, "{name}: {} capsules", envelope.len());
        assert!(envelope.pair_count() >= 1, "{name}");
        assert_eq!(envelope.first_hit(&placed), None, "{name}");
        let (gap, _) = envelope.nearest(&placed);
        assert!(gap.is_finite() && gap >= 0.0, "{name}: {gap}");
    }
}

/// `gaps` returns the nearest gap of what it did not visit: at home (nothing within the
/// margin) every robot's nearest gap; with everything within 5 cm visited, the nearest beyond.
#[test]
fn gaps_return_the_nearest_of_what_they_did_not_visit() {
    for (name, robot) in all_robots() {
        let (envelope, placed) = placed(&robot, &robot.home());
        let (gap, _) = envelope.nearest(&placed);
        let mut visited = 0;
        let beyond = envelope.gaps(&placed, None, 0.0, &mut |_, _, _| {
            visited += 1;
            true
        });
        assert_eq!((beyond, visited), (gap, 0), "{name}");
        let (mut all, mut near) = (Vec::new(), Vec::new());
        envelope.gaps(&placed, None, f64::INFINITY, &mut |_, g, _| {
            all.push(g);
            true
        });
        let beyond = envelope.gaps(&placed, None, 0.05, &mut |_, g, _| {
            near.push(g);
            true
        });
        let margin = envelope.margin();
        let expected = all
            .iter()
            .copied()
            .filter(|g| *g > margin + 0.05)
            .fold(f64::INFINITY, f64::min);
        assert_eq!(beyond, expected, "{name}");
        assert!(near.iter().all(|g| *g <= margin + 0.05), "{name}");
        assert_eq!(
            near.len() + all.iter().filter(|g| **g > margin + 0.05).count(),
            all.len()
        );
    }
}

#[test]
fn a_home_pose_in_collision_is_refused_naming_the_link_and_obstacle() {
    // ranger-mk1's stowed forearm lies 5.2 cm above the column: a 6 cm forearm reaches in.
    let mut config = robot("ranger-mk1").into_config();
    config.joints[2].link_radius = Some(0.06);
    let error = config.clone().validate().unwrap_err();
    let hit = Hit {
        link: 3,
        obstacle: Obstacle::Box(1),
    };
    assert_eq!(error.reason, ConfigReason::HomeInCollision(hit));
    assert!(
        error
            .to_string()
            .starts_with("collision: the home pose is already in collision: L3 hits B1"),
        "{error}"
    );
    // With the column gone the forearm and the tool still clear the bounds and each other.
    config.workspace.boxes.clear();
    config.validate().unwrap();

    // Another link: ur5's wrist folded back onto its upper arm, capsules 10 cm thick.
    let mut config = robot("ur5").into_config();
    for joint in &mut config.joints {
        joint.link_radius = Some(0.1);
    }
    let error = config.clone().validate().unwrap_err();
    assert!(
        matches!(
            error.reason,
            ConfigReason::HomeInCollision(Hit {
                obstacle: Obstacle::Link(_),
                ..
            })
        ),
        "{error}"
    );
    // Excluding every pair it names clears it, and an unknown link is refused.
    loop {
        match config.clone().validate() {
            Ok(_) => break,
            Err(e) => match e.reason {
                ConfigReason::HomeInCollision(Hit {
                    link,
                    obstacle: Obstacle::Link(other),
                }) => {
                    config.collision.exclude.push([link, other]).unwrap();
                }
                _ => panic!("{e}"),
            },
        }
    }
    config.collision.exclude.push([2, 7]).unwrap();
    assert_eq!(
        config.validate().unwrap_err().reason,
        ConfigReason::NoSuchLink
    );

    // The bounds: iiwa14 upright, its flange 4.4 cm under the ceiling, with a 5 cm margin.
    let mut config = robot("iiwa14").into_config();
    config.collision.margin = 0.05;
    let error = config.validate().unwrap_err();
    assert!(
        matches!(
            error.reason,
            ConfigReason::HomeInCollision(Hit {
                obstacle: Obstacle::Bounds,
                ..
            })
        ),
        "{error}"
    );
}

/// The bounds hold the tool's capsules; boxes keep out every link (docs/safety.md): ranger-mk1
/// at home with its elbow past a bound is clear while its tool is inside, and a bound under
/// the tool's shaft is a hit of link 6.
#[test]
fn the_bounds_hold_the_tool_and_boxes_keep_out_the_whole_arm() {
    let mut config = robot("ranger-mk1").into_config();
    // The elbow stands at y = 0.558, the tool's shaft at y = 0.02.
    config.workspace.bounds[3] = 0.3;
    let valid = config.clone().validate().unwrap();
    let (envelope, placed) = placed(&valid, &config.home());
    assert_eq!(envelope.first_hit(&placed), None);
    // The tool's shaft reaches from z = 0.402 to 0.666.
    config.workspace.bounds[5] = 0.6;
    let error = config.clone().validate().unwrap_err();
    let hit = Hit {
        link: 6,
        obstacle: Obstacle::Bounds,
    };
    assert_eq!(error.reason, ConfigReason::HomeInCollision(hit));
    // The same elbow in a box is a hit.
    config.workspace.bounds[5] = 2.0;
    config
        .workspace
        .boxes
        .push([-0.1, 0.1, 0.5, 0.6, 0.3, 0.5])
        .unwrap();
    let error = config.validate().unwrap_err();
    assert!(
        matches!(
            error.reason,
            ConfigReason::HomeInCollision(Hit {
                link: 2 | 3,
                obstacle: Obstacle::Box(2),
            })
        ),
        "{error}"
    );
}

#[test]
fn disabled_bodies_have_no_capsules() {
    let mut config = robot("ranger-mk1").into_config();
    config.joints[2].link_radius = None;
    config.collision.enabled = false;
    let (envelope, placed) = placed(&config.clone().validate().unwrap(), &config.home());
    assert!(envelope.is_empty());
    assert_eq!(envelope.first_hit(&placed), None);
}

/// The sweep bound: over a joint step from random poses, no point of any capsule (its ends
/// and points between, at any fraction of the step) moves further than the bound, in the world
/// and in the frame of every link inside it (what a pair's gap can close by).
#[test]
fn no_point_of_a_capsule_sweeps_further_than_the_bound() {
    let mut rng = SplitMix64::new(35);
    for (name, robot) in all_robots() {
        let chain = Chain::new(&robot);
        let envelope = Envelope::new(&robot);
        let links = robot.joints.len() as u8;
        for _ in 0..200 {
            let from = chain.random_joints(&mut rng);
            let mut step = from;
            for s in step.iter_mut() {
                *s = rng.uniform(-0.3, 0.3);
            }
            let (start, start_frames) = (place(&envelope, &robot, &from), frames_at(&robot, &from));
            for k in 1..=8 {
                let mut q = from;
                for (q, s) in q.iter_mut().zip(step.iter()) {
                    *q += s * f64::from(k) / 8.0;
                }
                let (now, frames) = (place(&envelope, &robot, &q), frames_at(&robot, &q));
                for c in 0..envelope.len() {
                    // Inner link 0 with the world's frame: the box's and the bounds' bound.
                    for inner in 0..=envelope.link_of(c).unwrap().min(links) {
                        let bound = envelope.sweep(c, &step, inner);
                        let (before, after) = if inner == 0 {
                            (Frame::identity(), Frame::identity())
                        } else {
                            let i = usize::from(inner);
                            (start_frames[i].inverse(), frames[i].inverse())
                        };
                        for t in [0.0, 0.3, 1.0] {
                            let was = before.transform_point(&start[c].segment.at(t).into());
                            let is = after.transform_point(&now[c].segment.at(t).into());
                            let moved = (is - was).norm();
                            assert!(
                                moved <= bound + 1e-12,
                                "{name} capsule {c} against link {inner}: {moved} > {bound}"
                            );
                        }
                    }
                }
            }
        }
    }
}
