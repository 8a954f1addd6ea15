//! The whole arm inside the envelope (issue 35): joint moves whose way would take a link into
//! a box, out of the bounds or into another link are refused before they start, with the link,
//! the obstacle and where named; what the check accepts, a dense walk of the way confirms; a
//! stream towards the base column is stopped before any link reaches it.
#![allow(
    clippy::approx_constant,
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod common;

use armgate_core::config::{Envelope, MAX_CAPSULES, Placed, ValidRobot, frames_at};
use armgate_core::geometry::Capsule;
use armgate_core::kinematics::{Chain, Joints};
use armgate_core::motion::{Body, Controller, Mode, Refusal};
use armgate_core::rng::SplitMix64;
use armgate_core::sim::{BodyOracle, IdealArm};
use armgate_protocol::client::{Hit, Hold, Obstacle, PathPoint};

/// ranger-mk1 in front of the base.
const MK1_READY: [f64; 6] = [1.5708, 0.6, -0.4, 0.2, 1.8, 0.1];
/// The measured repro of issue 35: from `MK1_READY` this joint move swings the forearm through
/// the base column (the tool just outside it, its shaft from the wrist centre through it; the
/// wrist centre ends 1.5 cm above it, 3.5 cm inside the seed's taller box).
const THROUGH_THE_COLUMN: [f64; 6] = [0.727, 1.084, 1.506, -2.849, 3.481, -1.322];

fn hits(envelope: &Envelope, config: &ValidRobot, q: &[f64]) -> Vec<Hit> {
    let mut placed: Placed = [Capsule::default(); MAX_CAPSULES];
    envelope.place(&frames_at(config, q), &mut placed);
    let mut all = Vec::new();
    envelope.hits(&placed, &mut |hit, _| {
        all.push(hit);
        true
    });
    all
}

/// The nearest gap of the body at `q` (m).
fn gap(envelope: &Envelope, config: &ValidRobot, q: &[f64]) -> f64 {
    let mut placed: Placed = [Capsule::default(); MAX_CAPSULES];
    envelope.place(&frames_at(config, q), &mut placed);
    envelope.nearest(&placed).0
}

fn joint_mode(config: &ValidRobot, q0: &[f64]) -> (Controller, IdealArm) {
    let mut ctrl = Controller::new(config);
    let arm = IdealArm::new(Joints::from_slice(q0).unwrap());
    ctrl.step(0.0, &arm.measured()).unwrap();
    ctrl.set_mode(Mode::Joint).unwrap();
    (ctrl, arm)
}

#[test]
fn a_joint_move_through_the_base_column_is_refused_naming_the_link() {
    let config = common::robot("ranger-mk1");
    // The goal itself: the tool's shaft (link 6) inside column box 1.
    let envelope = Envelope::new(&config);
    let at_goal = hits(&envelope, &config, &THROUGH_THE_COLUMN);
    let shaft_in_column = Hit {
        link: 6,
        obstacle: Obstacle::Box(1),
    };
    assert!(at_goal.contains(&shaft_in_column), "{at_goal:?}");
    assert!(hits(&envelope, &config, &MK1_READY).is_empty());

    let (mut ctrl, _) = joint_mode(&config, &MK1_READY);
    let refusal = ctrl.move_joints(&THROUGH_THE_COLUMN, 0.0).unwrap_err();
    let Refusal::Hits(hit, PathPoint::Along(percent)) = refusal else {
        panic!("{refusal:?}");
    };
    // The tool's shaft (link 6, from the wrist centre) enters the column first.
    assert_eq!(
        hit,
        Hit {
            link: 6,
            obstacle: Obstacle::Box(1)
        },
        "{refusal}"
    );
    assert!((1..=99).contains(&percent), "{refusal}");
    assert!(!ctrl.is_moving());
    // Back the other way, from inside: the forearm may leave the column.
    let (mut ctrl, _) = joint_mode(&config, &THROUGH_THE_COLUMN);
    ctrl.move_joints(&MK1_READY, 0.0).unwrap();
}

/// ranger-mk1's stowed home has the forearm and the tool 2 mm above the column: moves from
/// there, along it (joint 1 turns the arm about the column) or away, are accepted; the grown
/// check halves its pieces near the column rather than refusing for the growth alone.
#[test]
fn moves_that_pass_close_to_the_column_are_accepted() {
    let config = common::robot("ranger-mk1");
    let home = config.home();
    for (joint, by) in [(0, 0.5), (0, -1.0), (1, 0.3), (2, -0.4), (4, 0.5)] {
        let (mut ctrl, _) = joint_mode(&config, &home);
        let mut goal = home;
        goal[joint] += by;
        ctrl.move_joints(&goal, 0.0)
            .unwrap_or_else(|r| panic!("joint {} by {by}: {r}", joint + 1));
    }
}

/// Random joint moves of every shipped robot: whatever the sampled, grown check accepts, a
/// walk of 200 points along the way confirms (no hit that was not there at the start); and
/// the check refuses some, so it is not vacuous.
#[test]
fn accepted_joint_moves_never_touch_anything_on_the_way() {
    let mut rng = SplitMix64::new(35);
    let mut refused_anywhere = 0;
    for (name, config) in common::all_robots() {
        let chain = Chain::new(&config);
        let body = Body::new(&config);
        let envelope = body.envelope();
        let (mut accepted, mut refused) = (0, 0);
        for _ in 0..25 {
            let from = chain.random_joints(&mut rng);
            let mut to = from;
            for (q, (lo, hi)) in to.iter_mut().zip(chain.min().iter().zip(chain.max())) {
                *q = (*q + rng.uniform(-0.6, 0.6)).clamp(*lo, *hi);
            }
            let start = hits(envelope, &config, &from);
            if body.check_path(&chain, &from, &to).is_err() {
                refused += 1;
                continue;
            }
            accepted += 1;
            for k in 0..=200 {
                let mut q = from;
                for (q, (a, b)) in q.iter_mut().zip(from.iter().zip(to.iter())) {
                    *q = a + (b - a) * f64::from(k) / 200.0;
                }
                for hit in hits(envelope, &config, &q) {
                    assert!(
                        start.contains(&hit),
                        "{name}: {hit} at {k}/200 of an accepted move"
                    );
                }
            }
        }
        assert!(
            accepted > 0,
            "{name}: {accepted} accepted, {refused} refused"
        );
        refused_anywhere += refused;
    }
    assert!(refused_anywhere > 0);
}

/// A joint-rate stream along the repro's way: as the body nears the column the stream slows
/// down (no faster than a stop still ends within the gap, `clearance_scale`), then its look
/// ahead holds it before a link would come to rest in the column, naming the link and the box
/// (`WN13 Held: L6 hits B1`, the cause in force the workspace), one hold for as long as the
/// same command is sent; no stop is needed, and no measured pose ever has a link in the column.
#[test]
fn a_stream_towards_the_column_slows_and_holds_before_any_link_reaches_it() {
    let config = common::robot("ranger-mk1");
    let envelope = Envelope::new(&config);
    let (mut ctrl, mut arm) = joint_mode(&config, &MK1_READY);
    let step: Vec<f64> = THROUGH_THE_COLUMN
        .iter()
        .zip(MK1_READY)
        .map(|(b, a)| b - a)
        .collect();
    let longest = step.iter().fold(0.0f64, |m, s| m.max(s.abs()));
    let rates: Vec<f64> = step.iter().map(|s| s / longest * 0.07).collect();
    let period = config.control_period;
    let (mut held, mut holds) = (None, Vec::new());
    // (gap, joint speed) of every tick while moving.
    let mut trace = Vec::new();
    let mut last = arm.measured();
    for k in 1..4000 {
        ctrl.stream_joint_rates(&rates).unwrap();
        let out = ctrl.step(f64::from(k) * period, &arm.measured()).unwrap();
        arm.step(out.command.as_ref());
        let measured = arm.measured();
        assert!(
            hits(&envelope, &config, &measured).is_empty(),
            "tick {k}: {measured:?}"
        );
        assert_eq!(out.events.collision, None, "tick {k}");
        let speed = measured
            .iter()
            .zip(last.iter())
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
            / period;
        last = measured;
        if held.is_none() {
            trace.push((gap(&envelope, &config, &measured), speed));
        }
        if let Some(Hold::Contact(hit)) = out.events.hold {
            held.get_or_insert(k);
            if holds.last() != Some(&hit) {
                holds.push(hit);
            }
        } else {
            assert!(
                held.is_none(),
                "tick {k}: the hold ended under the same command"
            );
        }
        if held.is_some_and(|h| k > h + 200) {
            break;
        }
    }
    let held = held.expect("the stream never held");
    assert!(held > 10, "held at once: {held}");
    assert_eq!(
        holds,
        [Hit {
            link: 6,
            obstacle: Obstacle::Box(1)
        }]
    );
    assert_eq!(
        ctrl.stop_cause().0,
        Some(armgate_core::motion::StopCause::Workspace)
    );
    // At full speed while far, slower and slower over the last 5 cm before the hold.
    let full = 0.07 * 0.999;
    assert!(
        trace.iter().any(|(g, s)| *g > 0.2 && *s > full),
        "{trace:?}"
    );
    let near: Vec<_> = trace.iter().filter(|(g, _)| *g < 0.05).collect();
    assert!(near.len() > 5, "{near:?}");
    for pair in near.windows(2) {
        assert!(pair[1].1 <= pair[0].1 + 1e-9, "{pair:?}");
    }
    let (closest, slowest) = near.last().unwrap();
    let slowing = trace.iter().rev().find(|(_, s)| *s >= full).unwrap().0;
    eprintln!(
        "held at tick {held}, {closest} m from the box at {slowest} rad/s; slowing from {slowing} m"
    );
    assert!(*slowest < 0.5 * full, "{closest} m at {slowest} rad/s");
    // The gentle stop's distance: about ten times the 2 mm a full-deceleration stop needs.
    assert!((0.005..0.05).contains(&slowing), "{slowing}");
}

/// ur5's wrist links lie close by design: wrist 3's sphere (link 6) stays 1.2 cm from wrist
/// 1's capsule (link 4) whatever joint 5 does, wrist 3's capsule (link 5) 1.5 cm from the
/// forearm's (link 3) over most poses. A pair's gap closes only by the joints between its
/// links, so a long move past them is accepted (before, every capsule grew by the whole arm's
/// sweep: `L6 hits L4 at 53%` after 2,048 checks). The issue 33 plan move itself folds wrist 3
/// onto the forearm (their axes 2.85 cm apart at 73 %): refused, naming them.
#[test]
fn ur5s_wrist_passes_its_neighbours_but_not_through_its_forearm() {
    let config = common::robot("ur5");
    let chain = Chain::new(&config);
    let body = Body::new(&config);
    let joints = |q: [f64; 6]| Joints::from_slice(&q).unwrap();
    let start = joints([
        -2.425612749,
        -3.044014515,
        5.447551253,
        -3.2890222,
        4.74259444,
        4.336797611,
    ]);
    let plan_goal = joints([
        5.79917531,
        0.862840213,
        5.71650735,
        3.602384237,
        -6.188119895,
        1.181304767,
    ]);
    let clear_goal = joints([
        5.79917531,
        0.862840213,
        5.66650735,
        -2.68080107,
        -6.188119895,
        1.181304767,
    ]);
    body.check_path(&chain, &start, &clear_goal)
        .unwrap_or_else(|r| panic!("{r}"));
    let refusal = body.check_path(&chain, &start, &plan_goal).unwrap_err();
    let folded = Hit {
        link: 5,
        obstacle: Obstacle::Link(3),
    };
    assert!(
        matches!(refusal, Refusal::Hits(hit, PathPoint::Along(50..=73)) if hit == folded),
        "{refusal}"
    );
    // The check's work is capped by the period: 129 poses on ur5 (5.04 ms), 497 on
    // ranger-mk1 (19.44 ms); the clear way above took fewer.
    assert_eq!(body.max_checks(), 129);
    assert_eq!(Body::new(&common::robot("ranger-mk1")).max_checks(), 497);
}

/// A Cartesian line is checked for the whole arm at each point of its up-front check:
/// ranger-mk1's 3 cm step from home (the tool point far from everything) swings the elbow
/// round and 5.6 cm down, into a box put there; refused before the arm moves, naming the
/// forearm. Without the box the same line is accepted (`line_check.rs` runs it).
#[test]
fn a_cartesian_line_that_swings_the_elbow_into_a_box_is_refused() {
    let config = common::robot("ranger-mk1")
        .edit(|c| {
            c.workspace
                .boxes
                .push([0.3, 0.6, 0.2, 0.45, 0.3, 0.37])
                .unwrap()
        })
        .unwrap();
    let mut ctrl = Controller::new(&config);
    let arm = IdealArm::new(config.home());
    ctrl.step(0.0, &arm.measured()).unwrap();
    ctrl.set_mode(Mode::Cartesian).unwrap();
    let home = ctrl.chain().forward(&config.home()).unwrap();
    let mut there = home;
    there.translation.vector.x += 0.03;
    let refusal = ctrl.move_cartesian(there, 0.0).unwrap_err();
    assert!(
        matches!(
            refusal,
            Refusal::Hits(
                Hit {
                    link: 2 | 3,
                    obstacle: Obstacle::Box(2)
                },
                PathPoint::Along(_)
            )
        ),
        "{refusal}"
    );
    assert!(!ctrl.is_moving());
}

/// A collision stop brakes in joint space, where the tick's look-ahead ends it. hybrid's
/// unchecked line (`ik.check_lines = false`, as stop_bench's `WN22` case runs it) 0.6 m up
/// from stop_bench's start heads for a singularity, folding link 6 onto link 4: the tick saw the
/// stop's end in contact with 20 mm left, but braking along the path the joints slowed down
/// less than the path (0.41 of their 0.5 rad/s² instead of all of it) and the stop ended 4.5 mm
/// into link 4. Every commanded pose is held to the whole-arm oracle.
#[test]
fn a_collision_stop_on_an_unchecked_line_ends_before_contact() {
    let config = common::robot("hybrid")
        .edit(|c| c.ik.check_lines = false)
        .unwrap();
    let chain = Chain::new(&config);
    // stop_bench's start: mid-range, nudged.
    let mut q0 = chain.mid_range();
    for (i, q) in q0.iter_mut().enumerate() {
        let nudge = 0.12 * (chain.max()[i] - chain.min()[i]).min(2.0);
        *q += nudge * if i % 2 == 0 { 0.5 } else { -0.5 };
    }
    let (mut ctrl, mut arm) = (Controller::new(&config), IdealArm::new(q0));
    let mut oracle = BodyOracle::new(&config, &q0);
    ctrl.step(0.0, &arm.measured()).unwrap();
    ctrl.set_mode(Mode::Cartesian).unwrap();
    let mut goal = ctrl.cartesian_setpoint();
    goal.translation.vector.z += 0.6;
    ctrl.move_cartesian(goal, 0.0).unwrap();
    let mut collision = None;
    for k in 1..2000 {
        let out = ctrl
            .step(f64::from(k) * config.control_period, &arm.measured())
            .unwrap();
        arm.step(out.command.as_ref());
        collision = collision.or(out.events.collision);
        if let Some(q) = out.command {
            oracle
                .check(&q)
                .unwrap_or_else(|e| panic!("tick {k}: {} at gap {} m", e.hit, e.gap));
        }
        if !ctrl.is_moving() {
            break;
        }
    }
    let folding = Hit {
        link: 6,
        obstacle: Obstacle::Link(4),
    };
    assert_eq!(collision, Some(folding));
    let (gap, nearest) = oracle.nearest().unwrap();
    assert_eq!(nearest, folding);
    assert!(gap > 0.0, "{gap}");
}
