//! The control loop of the drive examples: a controller, the drive manager and a virtual bus
//! of simulated Whistles, stepped as the firmware steps them (receive → step → transmit).

use armgate_core::config::ValidRobot;
use armgate_core::drives::{DriveManager, DriveSettings, DriveState, VirtualBus};
use armgate_core::motion::{Controller, StepOutput};

/// One arm on one simulated bus.
pub struct DriveLoop {
    /// The simulated bus and its drives.
    pub bus: VirtualBus,
    /// The drive manager.
    pub manager: DriveManager,
    /// The controller.
    pub ctrl: Controller,
    period: f64,
    now: f64,
}

impl DriveLoop {
    /// Starts the drives on `bus` and ticks until they stream and the flow control has
    /// settled (20 more ticks).
    pub fn started(config: &ValidRobot, settings: &DriveSettings, bus: VirtualBus) -> Self {
        let mut l = Self {
            bus,
            manager: DriveManager::new(config, settings).unwrap(),
            ctrl: Controller::new(config),
            period: config.control_period,
            now: 0.0,
        };
        l.manager.start().unwrap();
        for _ in 0..500 {
            l.tick();
            if l.manager.state() != DriveState::Starting {
                break;
            }
        }
        assert!(l.manager.is_operational(), "{:?}", l.manager.fault());
        for _ in 0..20 {
            l.tick();
        }
        l
    }

    /// One control cycle.
    pub fn tick(&mut self) -> StepOutput {
        self.now += self.period;
        self.bus.advance(self.now).unwrap();
        self.manager.receive(&mut self.bus);
        let out = self.ctrl.step(self.now, &self.manager.measured()).unwrap();
        self.manager
            .transmit(self.now, out.command.as_ref(), &mut self.bus);
        out
    }

    /// Time of the last tick (s).
    pub fn now(&self) -> f64 {
        self.now
    }
}
