//! A controller and an ideal arm, stepped together at the robot's period: the rig of the
//! tests that drive `Controller` directly (no command handler, no drives).

use armgate_core::config::ValidRobot;
use armgate_core::kinematics::Joints;
use armgate_core::math::Frame;
use armgate_core::motion::{Controller, StepOutput};
use armgate_core::sim::IdealArm;

/// A controller and an ideal arm, stepped together at the robot's period.
pub struct ArmRig {
    pub ctrl: Controller,
    pub arm: IdealArm,
    pub period: f64,
    pub now: f64,
}

impl ArmRig {
    /// The rig at `q0`, after one tick (the controller has measured the arm).
    pub fn new(config: &ValidRobot, q0: &[f64]) -> Self {
        let mut rig = Self {
            ctrl: Controller::new(config),
            arm: IdealArm::new(Joints::from_slice(q0).unwrap()),
            period: config.control_period,
            now: 0.0,
        };
        rig.tick();
        rig
    }

    /// One control period: the controller steps, the arm follows its command.
    pub fn tick(&mut self) -> StepOutput {
        self.now += self.period;
        let out = self.ctrl.step(self.now, &self.arm.measured()).unwrap();
        self.arm.step(out.command.as_ref());
        out
    }

    /// Ticks until nothing moves (bounded), returning every output.
    pub fn settle(&mut self, max_ticks: usize) -> Vec<StepOutput> {
        let mut outs = Vec::new();
        for _ in 0..max_ticks {
            outs.push(self.tick());
            if !self.ctrl.is_moving() {
                break;
            }
        }
        assert!(
            !self.ctrl.is_moving(),
            "still moving after {max_ticks} ticks"
        );
        outs
    }

    /// The tool pose of the measured joints.
    pub fn pose(&self) -> Frame {
        self.ctrl.chain().forward(&self.arm.measured()).unwrap()
    }
}
