//! The core's control cycle on a virtual bus with simulated Whistles (the firmware's
//! `sim-drives` build without the network), for the drive tests and the drive examples.
#![allow(dead_code, clippy::unwrap_used, clippy::panic, clippy::approx_constant)]

pub mod frames;

use std::path::PathBuf;

use std::collections::VecDeque;

use armgate_core::config::{ValidRobot, load_file};
use armgate_core::cycle::{CanDrives, Cycle, Datagram, Dropped, Link, Outgoing};
use armgate_core::drives::{BusState, CanBus, DriveManager, DriveSettings, DriveState, TxError};
use armgate_core::kinematics::Joints;
use armgate_core::motion::{Controller, Mode, StepOutput};
use armgate_core::sim::VirtualBus;
use armgate_protocol::can::CanFrame;
use armgate_protocol::client::{Command, Request};

/// A ready pose of ranger-mk1 (rad): the arm raised, away from its joint limits.
pub const MK1_READY: [f64; 6] = [1.5708, 0.6, -0.4, 0.2, 1.8, 0.1];

/// A client request datagram with `command` and no values.
pub fn request(command: Command) -> Datagram<()> {
    let bytes = Request {
        command,
        values: [0.0; 7],
        index: 0,
    }
    .to_bytes();
    Datagram::new(&bytes, ())
}

/// Loads `robots/<name>.toml`.
pub fn robot(name: &str) -> ValidRobot {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../robots/{name}.toml"));
    load_file(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The core's control cycle with the drive manager on a virtual bus of simulated Whistles,
/// ticked on time: the firmware's `sim-drives` build without the network.
pub struct Rig {
    pub config: ValidRobot,
    pub cycle: Cycle<CanDrives<Recorder>, ()>,
    pub period: f64,
    /// Time of the last tick (s; read only).
    pub now: f64,
    /// The last command the controller produced.
    pub last_command: Option<Joints>,
    /// What the client would have received.
    pub client: Client,
}

impl Rig {
    pub fn new(config: ValidRobot) -> Self {
        Self::with(config, DriveSettings::default(), |_| {})
    }

    /// A rig whose bus is adjusted by `tweak` before anything runs; the drives idle until
    /// [`start`](Self::start).
    pub fn with(
        config: ValidRobot,
        settings: DriveSettings,
        tweak: impl FnOnce(&mut VirtualBus),
    ) -> Self {
        let mut bus = VirtualBus::for_robot(&config);
        tweak(&mut bus);
        Self::on(config, &settings, bus)
    }

    /// A rig on `bus`, the drives idle.
    pub fn on(config: ValidRobot, settings: &DriveSettings, bus: VirtualBus) -> Self {
        let drives = CanDrives::idle(
            &config,
            settings,
            Recorder {
                bus,
                sent: Vec::new(),
            },
        )
        .unwrap();
        Self {
            cycle: Cycle::new(&config, drives),
            period: config.control_period,
            now: 0.0,
            config,
            last_command: None,
            client: Client::default(),
        }
    }

    /// A rig on `bus` with the drives started and streaming, and the flow control settled
    /// (20 more ticks).
    pub fn started(config: &ValidRobot, settings: &DriveSettings, bus: VirtualBus) -> Self {
        let mut rig = Self::on(config.clone(), settings, bus);
        rig.start();
        rig.ticks(20);
        rig
    }

    /// One control cycle, on time: the bus runs up to the tick's time, the manager takes the
    /// answers, the controller steps on the measurement, the manager sends the command.
    pub fn tick(&mut self) -> StepOutput {
        let due = self.cycle.next_due_us();
        self.tick_at(due)
    }

    /// The same, with the shell's clock at `now_us` (late: the cycle catches up or skips).
    pub fn tick_at(&mut self, now_us: u64) -> StepOutput {
        self.cycle.drives_mut().bus_mut().sent.clear();
        let outcome = self.cycle.tick(now_us, &mut self.client);
        self.now = outcome.time;
        let out = outcome.step.unwrap();
        if out.command.is_some() {
            self.last_command = out.command;
        }
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

    /// [`started`](Self::started) with the default settings on the robot's own bus.
    pub fn running(config: &ValidRobot) -> Self {
        Self::started(
            config,
            &DriveSettings::default(),
            VirtualBus::for_robot(config),
        )
    }

    /// Moves ranger-mk1 back and forth between [`MK1_READY`] and home in joint mode for
    /// `seconds`, the drives operational throughout.
    pub fn shuttle(&mut self, seconds: f64) {
        self.ctrl_mut().set_mode(Mode::Joint).unwrap();
        let home = self.config.home();
        for k in 0..(seconds / self.period) as usize {
            if !self.ctrl().is_moving() {
                let goal: &[f64] = if k % 2 == 0 { &MK1_READY } else { &home };
                self.ctrl_mut().move_joints(goal, 0.0).unwrap();
            }
            self.tick();
            assert!(
                self.manager().is_operational(),
                "{:?} after {k}, lost {}",
                self.manager().fault(),
                self.bus().stats().frames_lost
            );
        }
    }

    /// Starts the drives and ticks until they stream; the ticks it took.
    pub fn start(&mut self) -> usize {
        self.manager_mut().start().unwrap();
        let ticks = self.until(200, |r| r.manager().state() != DriveState::Starting);
        assert_eq!(
            self.manager().state(),
            DriveState::Operational,
            "fault: {:?}",
            self.manager().fault()
        );
        ticks
    }

    pub fn ctrl(&self) -> &Controller {
        self.cycle.handler().controller()
    }

    pub fn ctrl_mut(&mut self) -> &mut Controller {
        self.cycle.handler_mut().controller_mut()
    }

    pub fn manager(&self) -> &DriveManager {
        self.cycle.drives().manager()
    }

    pub fn manager_mut(&mut self) -> &mut DriveManager {
        self.cycle.drives_mut().manager_mut()
    }

    pub fn bus(&self) -> &VirtualBus {
        &self.cycle.drives().bus().bus
    }

    pub fn bus_mut(&mut self) -> &mut VirtualBus {
        &mut self.cycle.drives_mut().bus_mut().bus
    }

    /// The frames the manager sent in the last tick.
    pub fn sent(&self) -> &[CanFrame] {
        &self.cycle.drives().bus().sent
    }

    /// The simulated drives' positions in joint units (joints with a drive only).
    pub fn drive_positions(&self) -> Vec<f64> {
        self.bus().drives().map(|d| d.joint_position()).collect()
    }

    /// Like [`tick`](Self::tick), returning the command if the manager took it (it was
    /// still streaming after the call).
    pub fn tick_accepted(&mut self) -> Option<Joints> {
        let out = self.tick();
        out.command.filter(|_| self.manager().is_operational())
    }
}

/// The client side of a rig: requests queued by the test, replies and notices kept.
#[derive(Default)]
pub struct Client {
    pub requests: VecDeque<Datagram<()>>,
    pub replies: Vec<Datagram<()>>,
    pub notices: Vec<Datagram<()>>,
}

impl Link<()> for Client {
    fn receive(&mut self) -> Option<Datagram<()>> {
        self.requests.pop_front()
    }

    fn send(&mut self, datagram: &Datagram<()>, kind: Outgoing) -> Result<(), Dropped> {
        match kind {
            Outgoing::Reply => self.replies.push(*datagram),
            Outgoing::Notice => self.notices.push(*datagram),
        }
        Ok(())
    }
}

/// The virtual bus, recording what the manager sends.
pub struct Recorder {
    pub bus: VirtualBus,
    pub sent: Vec<CanFrame>,
}

impl CanBus for Recorder {
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

    fn advance_to(&mut self, now: f64) -> bool {
        self.bus.advance_to(now)
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
