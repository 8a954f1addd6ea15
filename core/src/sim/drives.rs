//! Drives without a bus: a simulated arm behind the [`Drives`] interface.

use armgate_protocol::client::{DriveStatus, Text};

use super::arm::{IdealArm, RateLimitedArm};
use crate::command::Drives;
use crate::cycle::DriveSide;
use crate::drives::LifecycleError;
use crate::kinematics::Joints;
use crate::motion::Refusal;

/// Temperature the simulated drives report (°C).
const SIMULATED_TEMPERATURE: f64 = 30.0;

/// The arm model behind [`SimulatedDrives`].
// Unboxed on purpose: no heap, and there is one model per arm.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
pub enum ArmModel {
    /// Every command is reached at once (the seed's `SimArm`).
    Ideal(IdealArm),
    /// Joints follow with bounded velocity and acceleration.
    RateLimited(RateLimitedArm),
}

/// A simulated arm with the drives' start/stop state and recalibration, for running the whole
/// controller without CAN hardware. Running at construction, as the seed's robot auto-started.
#[derive(Clone, Debug)]
pub struct SimulatedDrives {
    model: ArmModel,
    running: bool,
    /// Reported position minus the model's position (changed by recalibration).
    offset: Joints,
}

impl SimulatedDrives {
    /// Simulated drives over an arm model.
    pub fn new(model: ArmModel) -> Self {
        let n = match &model {
            ArmModel::Ideal(arm) => arm.measured().len(),
            ArmModel::RateLimited(arm) => arm.measured().len(),
        };
        Self {
            model,
            running: true,
            offset: Joints::zeros(n),
        }
    }

    /// The measured joints, in the (possibly recalibrated) reported frame.
    pub fn measured(&self) -> Joints {
        let mut q = match &self.model {
            ArmModel::Ideal(arm) => arm.measured(),
            ArmModel::RateLimited(arm) => arm.measured(),
        };
        for (v, o) in q.iter_mut().zip(self.offset.iter()) {
            *v += o;
        }
        q
    }

    /// Applies one tick's command (`None`: hold) and advances the model by `dt` seconds. A
    /// stopped drive ignores commands.
    pub fn apply(&mut self, command: Option<&Joints>, dt: f64) {
        let raw = command.filter(|_| self.running).map(|c| {
            let mut raw = *c;
            for (v, o) in raw.iter_mut().zip(self.offset.iter()) {
                *v -= o;
            }
            raw
        });
        match &mut self.model {
            ArmModel::Ideal(arm) => arm.step(raw.as_ref()),
            ArmModel::RateLimited(arm) => arm.step(raw.as_ref(), dt),
        }
    }
}

impl Drives for SimulatedDrives {
    fn start(&mut self) -> Result<(), LifecycleError> {
        match core::mem::replace(&mut self.running, true) {
            false => Ok(()),
            true => Err(LifecycleError::Running),
        }
    }

    fn stop(&mut self) -> Result<(), LifecycleError> {
        match core::mem::replace(&mut self.running, false) {
            true => Ok(()),
            false => Err(LifecycleError::NotRunning),
        }
    }

    fn recalibrate(&mut self, q: &[f64]) -> Result<(), Refusal> {
        let current = self.measured();
        if q.len() != current.len() {
            return Err(Refusal::WrongJointCount);
        }
        if !q.iter().all(|v| v.is_finite()) {
            return Err(Refusal::InvalidNumber);
        }
        for ((o, target), now) in self.offset.iter_mut().zip(q).zip(current.iter()) {
            *o += target - now;
        }
        Ok(())
    }

    fn temperatures(&self) -> Joints {
        let mut t = Joints::zeros(self.offset.len());
        t.iter_mut().for_each(|v| *v = SIMULATED_TEMPERATURE);
        t
    }

    fn status(&self) -> DriveStatus {
        if self.running {
            DriveStatus::Running
        } else {
            DriveStatus::Off
        }
    }

    fn fault(&self) -> Option<Text> {
        None
    }

    fn fault_code(&self) -> Option<u8> {
        None
    }
}

/// A simulated arm without a bus: commands reach the arm model directly.
impl DriveSide for SimulatedDrives {
    fn receive(&mut self, _now: f64) -> bool {
        true
    }

    fn measured(&self) -> Joints {
        SimulatedDrives::measured(self)
    }

    fn transmit(&mut self, _now: f64, elapsed: f64, command: Option<&Joints>) {
        self.apply(command, elapsed);
    }
}
