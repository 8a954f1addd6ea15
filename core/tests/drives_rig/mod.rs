//! A controller, the drive manager and a virtual bus with simulated Whistles, stepped together
//! as the firmware's control loop steps them.
#![allow(dead_code, clippy::unwrap_used, clippy::panic)]

use std::path::PathBuf;

use std::collections::VecDeque;

use armgate_core::config::{ValidRobot, load_file};
use armgate_core::drives::{
    BusState, CanBus, DriveManager, DriveSettings, DriveState, TxError, VirtualBus,
};
use armgate_core::kinematics::Joints;
use armgate_core::motion::{Controller, StepOutput};
use armgate_protocol::can::CanFrame;

/// Loads `robots/<name>.toml`.
pub fn robot(name: &str) -> ValidRobot {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../robots/{name}.toml"));
    load_file(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

pub struct Rig {
    pub config: ValidRobot,
    pub manager: DriveManager,
    pub bus: VirtualBus,
    pub ctrl: Controller,
    pub period: f64,
    pub now: f64,
    /// The last command the controller produced.
    pub last_command: Option<Joints>,
    /// The frames the manager sent in the last tick.
    pub sent: Vec<CanFrame>,
}

impl Rig {
    pub fn new(config: ValidRobot) -> Self {
        Self::with(config, DriveSettings::default(), |_| {})
    }

    /// A rig whose bus is adjusted by `tweak` before anything runs.
    pub fn with(
        config: ValidRobot,
        settings: DriveSettings,
        tweak: impl FnOnce(&mut VirtualBus),
    ) -> Self {
        let mut bus = VirtualBus::for_robot(&config);
        tweak(&mut bus);
        Self {
            manager: DriveManager::new(&config, &settings).unwrap(),
            ctrl: Controller::new(&config),
            period: config.control_period,
            config,
            bus,
            now: 0.0,
            last_command: None,
            sent: Vec::new(),
        }
    }

    /// One control cycle: the bus runs up to now, the manager takes the answers, the
    /// controller steps on the measurement, the manager sends the command.
    pub fn tick(&mut self) -> StepOutput {
        self.now += self.period;
        self.bus.advance(self.now).unwrap();
        self.manager.receive(&mut self.bus);
        let out = self.ctrl.step(self.now, &self.manager.measured()).unwrap();
        if out.command.is_some() {
            self.last_command = out.command;
        }
        let mut recorder = Recorder {
            bus: &mut self.bus,
            sent: Vec::new(),
        };
        self.manager
            .transmit(self.now, out.command.as_ref(), &mut recorder);
        self.sent = recorder.sent;
        out
    }

    /// Ticks `n` times.
    pub fn ticks(&mut self, n: usize) {
        for _ in 0..n {
            self.tick();
        }
    }

    /// Ticks until `done` (at most `max` ticks); the number of ticks taken.
    pub fn until(&mut self, max: usize, mut done: impl FnMut(&Self) -> bool) -> usize {
        for k in 0..max {
            if done(self) {
                return k;
            }
            self.tick();
        }
        assert!(done(self), "condition not reached in {max} ticks");
        max
    }

    /// Starts the drives and ticks until they stream; the ticks it took.
    pub fn start(&mut self) -> usize {
        self.manager.start().unwrap();
        let ticks = self.until(200, |r| r.manager.state() != DriveState::Starting);
        assert_eq!(
            self.manager.state(),
            DriveState::Operational,
            "fault: {:?}",
            self.manager.fault()
        );
        ticks
    }

    /// The simulated drives' positions in joint units (joints with a drive only).
    pub fn drive_positions(&self) -> Vec<f64> {
        self.bus.drives().map(|d| d.joint_position()).collect()
    }
}

/// A rig that also remembers the last command the manager took.
impl Rig {
    /// Like [`tick`](Self::tick), returning the command if the manager took it (it was
    /// still streaming after the call).
    pub fn tick_accepted(&mut self) -> Option<armgate_core::kinematics::Joints> {
        let out = self.tick();
        out.command.filter(|_| self.manager.is_operational())
    }
}

/// Forwards to a bus and records what was sent.
pub struct Recorder<'a, B: CanBus> {
    pub bus: &'a mut B,
    pub sent: Vec<CanFrame>,
}

impl<B: CanBus> CanBus for Recorder<'_, B> {
    fn try_transmit(&mut self, frame: &CanFrame) -> Result<(), TxError> {
        self.bus.try_transmit(frame)?;
        self.sent.push(*frame);
        Ok(())
    }

    fn try_receive(&mut self) -> Option<CanFrame> {
        self.bus.try_receive()
    }

    fn state(&self) -> BusState {
        self.bus.state()
    }
}

/// A bus played by the test: it keeps what the manager sends and hands over what the test
/// queues.
#[derive(Default)]
pub struct ScriptedBus {
    pub sent: Vec<CanFrame>,
    pub inbox: VecDeque<CanFrame>,
    pub bus_off: bool,
    /// Refuse every frame with this error.
    pub refuse: Option<TxError>,
}

impl ScriptedBus {
    /// Takes what was sent so far.
    pub fn take(&mut self) -> Vec<CanFrame> {
        std::mem::take(&mut self.sent)
    }
}

impl CanBus for ScriptedBus {
    fn try_transmit(&mut self, frame: &CanFrame) -> Result<(), TxError> {
        if let Some(error) = self.refuse {
            return Err(error);
        }
        self.sent.push(*frame);
        Ok(())
    }

    fn try_receive(&mut self) -> Option<CanFrame> {
        self.inbox.pop_front()
    }

    fn state(&self) -> BusState {
        BusState::from_bus_off(self.bus_off)
    }
}
