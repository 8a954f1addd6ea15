//! The drive side of the arm, chosen at build time in this one place.
//!
//! The control task needs, besides the core's [`Drives`] interface (ON, OF, RC, TM), the measured
//! joints before a tick and a place to put the tick's command: that is [`Arm`].
//!
//! * feature `sim-drives` (the default for now): the core's `SimulatedDrives` run inside the
//!   firmware (ideal or rate-limited arm, `ARMGATE_SIM_ARM`), starting at the drives' home
//!   positions, so a bare board can be commanded over UDP with no arm attached;
//! * without it: the core's CANopen drive manager (`core/src/drives`) on FDCAN1. It is not wired
//!   into the firmware yet, and such a build stops with a message. Its `Arm` implementation goes
//!   here: `measured` returns the positions the drives last reported, `apply` hands the tick's
//!   command to the manager, which writes the PT set-point frames into the FDCAN TX FIFO.

use armgate_core::command::Drives;
use armgate_core::kinematics::Joints;

/// The arm as the control task drives it: the command side of the core ([`Drives`]) plus the
/// measurement before a tick and the command after it.
pub trait Arm: Drives {
    /// The joint positions the tick starts from (rad or m, one per joint).
    fn measured(&self) -> Joints;
    /// Sends one tick's command (`None`: hold the last one); `dt` is the control period (s).
    fn apply(&mut self, command: Option<&Joints>, dt: f64);
}

#[cfg(feature = "sim-drives")]
pub use simulated::{BoardDrives, describe, new};

#[cfg(not(feature = "sim-drives"))]
compile_error!(
    "the CAN drive path (the CANopen drive manager on FDCAN1) is not wired into the firmware \
     yet: build it with the default feature `sim-drives`"
);

#[cfg(feature = "sim-drives")]
mod simulated {
    use armgate_core::command::{ArmModel, SimulatedDrives};
    use armgate_core::config::RobotConfig;
    use armgate_core::kinematics::Joints;
    use armgate_core::motion::{IdealArm, RateLimitedArm};

    use super::Arm;
    use crate::settings::{SIM_ARM, SimArm};

    /// The drives this build runs: simulated.
    pub type BoardDrives = SimulatedDrives;

    impl Arm for SimulatedDrives {
        fn measured(&self) -> Joints {
            SimulatedDrives::measured(self)
        }

        fn apply(&mut self, command: Option<&Joints>, dt: f64) {
            SimulatedDrives::apply(self, command, dt);
        }
    }

    /// Simulated drives at the robot's home positions, running (as the seed's robot
    /// auto-started), with the dynamics chosen by `ARMGATE_SIM_ARM`.
    pub fn new(robot: &RobotConfig) -> BoardDrives {
        let n = robot.dof();
        let mut home = Joints::zeros(n);
        let mut v_max = Joints::zeros(n);
        let mut a_max = Joints::zeros(n);
        for (j, ((q, v), a)) in robot
            .joints
            .iter()
            .zip(home.iter_mut().zip(v_max.iter_mut()).zip(a_max.iter_mut()))
        {
            *q = j.drive.home;
            *v = j.max_rate;
            *a = j.max_acceleration;
        }
        let model = match SIM_ARM {
            SimArm::Ideal => ArmModel::Ideal(IdealArm::new(home)),
            SimArm::RateLimited => ArmModel::RateLimited(RateLimitedArm::new(home, v_max, a_max)),
        };
        SimulatedDrives::new(model)
    }

    /// What [`new`] builds, for the boot log.
    pub fn describe() -> &'static str {
        match SIM_ARM {
            SimArm::Ideal => "simulated drives, ideal arm",
            SimArm::RateLimited => "simulated drives, rate-limited arm",
        }
    }
}
