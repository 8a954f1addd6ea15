//! Accepted motions run to their end (issue 35): a joint move whose whole way the body check
//! accepted is never stopped by the tick's check of the same body (`ER21`).
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod common;

use armgate_core::config::{MAX_CAPSULES, Placed, ValidRobot, frames_at};
use armgate_core::geometry::Capsule;
use armgate_core::kinematics::{Chain, Joints};
use armgate_core::motion::{Body, Mode, Refusal};
use armgate_core::rng::SplitMix64;
use armgate_protocol::client::{Hit, Obstacle};
use common::arm_rig::ArmRig;

/// `config` with the measuring tests' fast joints: 3 rad/s, 6 rad/s².
fn fast(config: ValidRobot) -> ValidRobot {
    config
        .edit(|c| {
            for j in c.joints.iter_mut() {
                j.max_velocity = 3.0;
                j.max_acceleration = 6.0;
                j.max_rate = 3.1;
                j.drive.max_speed = 3.1;
            }
        })
        .unwrap()
}

/// Runs the joint move `from` → `to` to its end; the tick on which a collision stopped it.
fn run(config: &ValidRobot, from: &[f64], to: &[f64]) -> Option<(usize, String)> {
    let mut rig = ArmRig::new(config, from);
    rig.ctrl.set_mode(Mode::Joint).unwrap();
    rig.ctrl
        .move_joints(to, 0.0)
        .unwrap_or_else(|r| panic!("refused: {r}"));
    run_to_end(&mut rig)
}

/// Steps `rig` until its motion ends; the tick on which a collision stopped it, and where.
fn run_to_end(rig: &mut ArmRig) -> Option<(usize, String)> {
    for k in 0..20_000 {
        let out = rig.tick();
        if let Some(hit) = out.events.collision {
            return Some((k, format!("{hit} at {:?}", out.command)));
        }
        if !rig.ctrl.is_moving() {
            return None;
        }
    }
    panic!("still moving");
}

/// The two moves of the measuring run on the fast ranger-mk1 that were accepted and then
/// stopped `ER21 L3 hits B1` and `ER21 L6 hits B1` (plan poses 12 → 1 and 6 → 8).
#[test]
fn the_measuring_runs_accepted_moves_reach_their_goals() {
    let config = fast(common::robot("ranger-mk1"));
    let moves = [
        (
            [
                -2.936877985,
                -0.732554269,
                -2.308815072,
                0.317125886,
                1.047178267,
                -2.196866679,
            ],
            [
                2.510108487,
                -0.431246054,
                1.44249684,
                -2.012724822,
                3.844183836,
                1.411328162,
            ],
        ),
        (
            [
                0.04058719,
                -0.538976659,
                -2.104520105,
                -1.913769489,
                2.422158451,
                -2.011300671,
            ],
            [
                -1.880233449,
                1.638680175,
                1.289460837,
                -2.468512018,
                0.937883084,
                0.802724123,
            ],
        ),
    ];
    for (from, to) in moves {
        assert_eq!(run(&config, &from, &to), None, "{from:?} -> {to:?}");
    }
}

/// True if no capsule of `config`'s body is within the margin of anything at `q`.
fn clear(config: &ValidRobot, body: &Body, q: &[f64]) -> bool {
    let mut placed: Placed = [Capsule::default(); MAX_CAPSULES];
    body.envelope().place(&frames_at(config, q), &mut placed);
    body.envelope().first_hit(&placed).is_none()
}

/// Random joint moves between clear poses of ranger-mk1, ur5 and puma560, all at 3 rad/s and
/// 6 rad/s² (ur5's file: π/2 rad/s): every move the controller accepts runs to its goal with no `ER21`.
/// Half the goals are anywhere within the limits, half near the start; some are refused, so
/// the moves accepted are not only the easy ones.
#[test]
fn every_accepted_joint_move_of_a_fast_arm_runs_to_its_goal() {
    let mut rng = SplitMix64::new(3521);
    for config in [
        fast(common::robot("ranger-mk1")),
        fast(common::robot("ur5")),
        // A table in front of puma560, below the shoulder: its file has no boxes.
        fast(common::robot("puma560"))
            .edit(|c| {
                c.workspace
                    .boxes
                    .push([0.25, 0.8, -0.8, 0.8, -0.6, -0.25])
                    .unwrap()
            })
            .unwrap(),
    ] {
        let (chain, body) = (Chain::new(&config), Body::new(&config));
        let (mut accepted, mut refused) = (0, 0);
        while accepted < 20 {
            let from = chain.random_joints(&mut rng);
            if !clear(&config, &body, &from) {
                continue;
            }
            let mut to = chain.random_joints(&mut rng);
            if accepted % 2 == 0 {
                for ((t, f), (lo, hi)) in to
                    .iter_mut()
                    .zip(from.iter())
                    .zip(chain.min().iter().zip(chain.max()))
                {
                    *t = (f + rng.uniform(-0.8, 0.8)).clamp(*lo, *hi);
                }
            }
            let mut rig = ArmRig::new(&config, &from);
            rig.ctrl.set_mode(Mode::Joint).unwrap();
            if rig.ctrl.move_joints(&to, 0.0).is_err() {
                refused += 1;
                continue;
            }
            accepted += 1;
            assert_eq!(
                run_to_end(&mut rig),
                None,
                "{}: {from:?} -> {to:?}",
                config.name
            );
            assert_eq!(rig.ctrl.command().unwrap(), to, "{}", config.name);
        }
        eprintln!("{}: {accepted} accepted, {refused} refused", config.name);
        assert!(refused > 0, "{}: none refused", config.name);
    }
}

/// Random Cartesian lines (`BG`) of 5 to 40 cm from clear poses of the same fast robots, their
/// lines at 0.5 m/s and 1 m/s² (ur5's file: 0.25 m/s): every line the controller accepts runs
/// to its goal with no `ER21`. (A longer run, 60 lines each, found none either.)
#[test]
fn every_accepted_cartesian_line_of_a_fast_arm_runs_to_its_goal() {
    let mut rng = SplitMix64::new(3522);
    for config in [
        fast(common::robot("ranger-mk1")),
        fast(common::robot("ur5")),
    ] {
        let config = config
            .edit(|c| {
                c.cartesian.max_velocity = [0.5, 0.5, 0.5, 1.0, 1.0, 1.0];
                c.cartesian.max_acceleration = [1.0, 1.0, 1.0, 2.0, 2.0, 2.0];
            })
            .unwrap();
        let (chain, body) = (Chain::new(&config), Body::new(&config));
        let (mut accepted, mut refused) = (0, 0);
        while accepted < 8 {
            let from = chain.random_joints(&mut rng);
            if !clear(&config, &body, &from) {
                continue;
            }
            let mut to = chain.forward(&from).unwrap();
            let length = rng.uniform(0.05, 0.4);
            let direction = armgate_core::math::Vector3::new(
                rng.uniform(-1.0, 1.0),
                rng.uniform(-1.0, 1.0),
                rng.uniform(-1.0, 1.0),
            )
            .normalize();
            to.translation.vector += direction * length;
            let mut rig = ArmRig::new(&config, &from);
            rig.ctrl.set_mode(Mode::Cartesian).unwrap();
            if rig.ctrl.move_cartesian(to, 0.0).is_err() {
                refused += 1;
                continue;
            }
            accepted += 1;
            assert_eq!(
                run_to_end(&mut rig),
                None,
                "{}: {from:?} -> {to:?}",
                config.name
            );
        }
        eprintln!("{}: {accepted} accepted, {refused} refused", config.name);
        assert!(refused > 0, "{}: none refused", config.name);
    }
}

/// ur5 at rest with its forearm 0.9 mm from its base (within `CONTACT`, 1 mm, of the margin, 0,
/// but not a hit): a move that folds the forearm through the base is refused. Before, the
/// check let what was that near at the start pass for the whole way, and the tick's check
/// (which counts it as new once within the margin) stopped the accepted move `L3 hits L0`
/// four ticks in. Moves away from it are still accepted.
///
#[test]
fn a_link_just_clear_of_another_is_not_let_through_it() {
    let config = fast(common::robot("ur5"));
    let (chain, body) = (Chain::new(&config), Body::new(&config));
    let from = Joints::from_slice(&[
        -2.8808447739392786,
        5.164879177452281,
        -3.3230441033524754,
        5.9012290221316395,
        4.3486558286746675,
        -4.0636339021382994,
    ])
    .unwrap();
    let through = Joints::from_slice(&[
        5.404175052340941,
        2.5725463023291866,
        2.7172765792778915,
        5.924293650489592,
        -5.658088905551795,
        4.510729007123992,
    ])
    .unwrap();
    let (gap, nearest) = {
        let mut placed: Placed = [Capsule::default(); MAX_CAPSULES];
        body.envelope()
            .place(&frames_at(&config, &from), &mut placed);
        body.envelope().nearest(&placed)
    };
    let forearm_on_base = Hit {
        link: 3,
        obstacle: Obstacle::Link(0),
    };
    assert_eq!(nearest, Some(forearm_on_base));
    assert!(gap > 0.0 && gap < 0.001, "{gap}");
    let refusal = body.check_path(&chain, &from, &through).unwrap_err();
    assert!(
        matches!(
            refusal,
            Refusal::Hits(hit, _) if hit == forearm_on_base
        ) || matches!(refusal, Refusal::NearEdge(_)),
        "{refusal}"
    );
    // Back the way it came: away from the base.
    let mut away = from;
    for (a, t) in away.iter_mut().zip(through.iter()) {
        *a -= 0.05 * (t - *a);
    }
    body.check_path(&chain, &from, &away)
        .unwrap_or_else(|r| panic!("{r}"));
    assert_eq!(run(&config, &from, &away), None);
}
