//! Accepted motions run to their end (issue 35): a joint move whose whole way the body check
//! accepted is never stopped by the tick's check of the same body (`ER21`).
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod common;

use armgate_core::config::ValidRobot;
use armgate_core::motion::Mode;
use common::arm_rig::ArmRig;

/// ranger-mk1 with the measuring tests' fast joints: 3 rad/s, 6 rad/s².
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
