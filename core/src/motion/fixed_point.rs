//! The tracking solve's fixed point, remembered so that a holding arm does not solve again.
//!
//! While a Cartesian motion holds (its generator idle), every tick asks the tracking IK for the
//! same set-point from the last command, and once that command is the solve's own answer the
//! solve returns it unchanged, tick after tick: a forward kinematics, the pose error and the
//! checks (≈ 2,500 instructions a tick on the Cortex-M7, qemu-bench) for the answer the tick
//! before gave. The solve is a pure function of the set-point and the seed (the chain, the IK
//! settings and the joint limits never change after start), so when both are bit for bit those
//! of a solve that returned its seed, its answer is that seed again; nothing else is remembered
//! or assumed.

use crate::kinematics::Joints;
use crate::math::Frame;

/// A set-point and the joints that the tracking solve (and the rate check) returned unchanged
/// when seeded with them.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct FixedPoint {
    solved: Option<(Frame, Joints)>,
}

impl FixedPoint {
    /// True if the solve of `setpoint` from `seed` is known to return `seed`.
    pub(super) fn holds(&self, setpoint: &Frame, seed: &Joints) -> bool {
        self.solved
            .as_ref()
            .is_some_and(|(pose, q)| same_joints(q, seed) && same_frame(pose, setpoint))
    }

    /// Takes note of a solve of `setpoint` from `seed` that was reached at `q`: remembered if
    /// `q` is `seed` itself.
    pub(super) fn note(&mut self, setpoint: &Frame, seed: &Joints, q: &Joints) {
        if same_joints(q, seed) {
            self.solved = Some((*setpoint, *seed));
        }
    }
}

/// Bit for bit equal (so `-0.0` and `0.0` differ and a NaN equals itself: only an identical
/// input counts).
fn same_joints(a: &Joints, b: &Joints) -> bool {
    a.len() == b.len() && same_bits(a.as_array(), b.as_array())
}

fn same_frame(a: &Frame, b: &Frame) -> bool {
    same_bits(
        a.translation.vector.as_slice(),
        b.translation.vector.as_slice(),
    ) && same_bits(
        a.rotation.matrix().as_slice(),
        b.rotation.matrix().as_slice(),
    )
}

fn same_bits(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::math::{Rotation3, Vector3};
    use crate::motion::{Controller, Mode};
    use crate::sim::IdealArm;

    fn pose(x: f64) -> Frame {
        Frame::from_parts(
            Vector3::new(x, 0.2, 0.3).into(),
            Rotation3::from_euler_angles(0.1, 0.2, 0.3),
        )
    }

    fn joints(values: &[f64]) -> Joints {
        Joints::from_slice(values).unwrap()
    }

    #[test]
    fn only_a_solve_that_returned_its_seed_is_remembered() {
        let mut fixed = FixedPoint::default();
        let (seed, other) = (joints(&[0.1, 0.2, 0.3]), joints(&[0.1, 0.2, 0.31]));
        assert!(!fixed.holds(&pose(0.5), &seed));
        fixed.note(&pose(0.5), &seed, &other);
        assert!(
            !fixed.holds(&pose(0.5), &seed),
            "the solve moved the joints"
        );
        fixed.note(&pose(0.5), &seed, &seed);
        assert!(fixed.holds(&pose(0.5), &seed));
    }

    #[test]
    fn any_other_input_bit_is_a_different_solve() {
        let mut fixed = FixedPoint::default();
        let seed = joints(&[0.1, 0.0, 0.3]);
        fixed.note(&pose(0.5), &seed, &seed);
        assert!(!fixed.holds(&pose(0.5 + 1e-16), &seed));
        assert!(!fixed.holds(&pose(0.5), &joints(&[0.1, -0.0, 0.3])));
        assert!(!fixed.holds(&pose(0.5), &joints(&[0.1, 0.0, 0.3, 0.0])));
        let mut turned = pose(0.5);
        turned.rotation = Rotation3::from_euler_angles(0.1, 0.2, 0.3 + 1e-15);
        assert!(!fixed.holds(&turned, &seed));
        assert!(fixed.holds(&pose(0.5), &seed));
    }

    /// Through a Cartesian move and the hold after it, every command is bit for bit what the
    /// tracking solve gives from the command before; while holding, the solve is skipped.
    #[test]
    fn a_holding_arm_gets_the_solve_it_skips() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../robots/ranger-mk1.toml");
        let config = crate::config::load_file(path).unwrap();
        let start = [core::f64::consts::FRAC_PI_2, 0.6, -0.4, 0.2, 1.8, 0.1];
        let mut arm = IdealArm::new(Joints::from_slice(&start).unwrap());
        let mut ctrl = Controller::new(&config);
        let mut now = 0.0;
        let mut tick = |ctrl: &mut Controller, arm: &mut IdealArm| {
            now += config.control_period;
            let out = ctrl.step(now, &arm.measured()).unwrap();
            arm.step(out.command.as_ref());
            out
        };
        tick(&mut ctrl, &mut arm);
        ctrl.set_mode(Mode::Cartesian).unwrap();
        let mut previous = tick(&mut ctrl, &mut arm).command.unwrap();
        let mut goal = ctrl.cartesian_setpoint();
        goal.translation.vector += Vector3::new(0.03, -0.02, 0.01);
        ctrl.move_cartesian(goal, 0.0).unwrap();
        let (mut moving, mut held) = (0, 0);
        for _ in 0..2_000 {
            let out = tick(&mut ctrl, &mut arm);
            let (setpoint, command) = (out.setpoint.unwrap(), out.command.unwrap());
            let solved = ctrl
                .chain()
                .solve_tracking(&setpoint, &previous, &config.ik)
                .unwrap();
            assert!(same_joints(&command, &solved.solution().q));
            if ctrl.is_moving() {
                moving += 1;
            } else {
                held += 1;
                // The first tick at rest commands the goal; from then on the arm stays.
                assert!(
                    held == 1 || same_joints(&command, &previous),
                    "the arm stays"
                );
                if held == 50 {
                    break;
                }
            }
            previous = command;
        }
        assert!(
            moving > 10 && held == 50,
            "{moving} moving, {held} held ticks"
        );
    }
}
