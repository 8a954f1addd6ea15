//! One full control tick of the core, as the firmware runs it: [`CommandHandler`] with the
//! CANopen [`DriveManager`] on a [`VirtualBus`] of simulated Whistles (the firmware's
//! `sim-drives` build), in Cartesian mode, during a straight-line move started with datagrams
//! (`CM 2`, `GT`, `BG`), on the robots of [`TICK_ROBOTS`]. The drives start (NMT, configuration,
//! PT initialisation) before the move, as at the firmware's power-up.
//!
//! The move runs three times from the same start; the core is deterministic, so every pass
//! does the same work.
//!
//! 1. **Whole tick**: one window per tick around what the firmware's control task does when no
//!    request waits: `manager.receive`, `manager.measured()`, `handler.tick`,
//!    `manager.transmit`, draining the notices ([`Session::tick`]; each step is a function of
//!    its own, not inlined, so that pass 2 times the same code). The virtual bus's `advance`
//!    (the simulated Whistles and the bus: on a board with real drives, the drives and the
//!    FDCAN peripheral) runs before it, in a window of its own.
//! 2. **Breakdown**: each of those steps in a window of its own (the drive manager's two halves
//!    summed per tick), plus replicas that run beside the handler with the same inputs: a second [`Controller`] given the same requests
//!    (`Controller::step`; its command is checked against the handler's every tick), and the
//!    calls a Cartesian `step` makes: FK of the measured joints (`Chain::forward`), the
//!    generator (a second `CartesianGenerator` with the same move: `sample` + `advance_to`),
//!    the workspace check (`Workspace::allows` of the measured pose and the set-point), tracking
//!    IK from the last command to the tick's set-point (`Chain::solve_tracking`) and the joint
//!    limiter (`JointLimiter::rate_ratio` + `limit`). What `step` does besides (input check,
//!    sequence poll, mode switch, events, copies of the state) is `step` minus those; the notice
//!    relay is `handler.tick` minus `step`.
//! 3. **Stack**: the stack is painted below the caller, the requests and ticks run again, and
//!    the lowest word written gives the stack the control work needs.

use core::f64::consts::FRAC_PI_2;

use armgate_core::command::CommandHandler;
use armgate_core::config::{RobotConfig, ValidRobot};
use armgate_core::drives::{DriveManager, DriveSettings, VirtualBus};
use armgate_core::kinematics::{Chain, Joints, KinematicsError};
use armgate_core::math::{self, Frame, Rotation3, Vector3};
use armgate_core::motion::{
    CartesianGenerator, Controller, JointLimiter, Mode, StepOutput, Workspace,
};
use armgate_protocol::client::{Command, MESSAGE_LEN, Request, VALUES};
use cortex_m_semihosting::hprintln;

use crate::counter::{Counter, Timing, measure};
use crate::stack;

include!(concat!(env!("OUT_DIR"), "/robots.rs"));

/// The robots measured, each from a well-conditioned start (joint angles, rad) from which the
/// arm follows the move at full speed. At its home pose ranger-mk1 is close to a singularity:
/// the joint rate limits slow the same move down and ticks retry the IK at smaller steps, which
/// is measured as a row of its own ([`HOME_ROBOT`]). ranger-mk2's home is the stretched zero
/// pose, a singularity.
const TICK_ROBOTS: [(&str, &[f64]); 2] = [
    ("ranger-mk1", &[FRAC_PI_2, 0.8, 0.5, 0.5, 1.5, 0.5]),
    ("ranger-mk2", &[0.3, 0.5, 0.3, 1.0, 0.3, 0.8, 0.3, 0.5]),
];
/// The robot also measured from its home pose.
const HOME_ROBOT: &str = "ranger-mk1";
/// The move: from the start pose by this much (m) along x, y, z ...
const OFFSET: [f64; 3] = [0.05, -0.05, 0.05];
/// ... turning the tool by this much (rad) in yaw ...
const TURN: f64 = 0.1;
/// ... in at least this long (s).
const MIN_DURATION: f64 = 4.0;
/// Upper bound on the ticks of the move.
const MAX_TICKS: u32 = 2_000;
/// Ticks measured after the move, the arm holding in Cartesian mode.
const HOLD_TICKS: u32 = 50;
/// PS requests measured after the move.
const POSE_REQUESTS: u32 = 20;
/// Ticks the drives may take to start (12 with drives already in position mode).
const START_TICKS: u32 = 100;
/// Stack painted below the caller for the high-water mark (bytes).
const STACK_DEPTH: usize = 32 * 1024;

/// The firmware's control state with `sim-drives`: a handler, the drive manager, the virtual
/// bus with a simulated Whistle per drive, and the time of the next tick.
struct Session<'a> {
    config: &'a ValidRobot,
    handler: CommandHandler,
    manager: DriveManager,
    bus: VirtualBus,
    time: f64,
}

impl<'a> Session<'a> {
    /// The drives at `start` (or at their home positions), started (the firmware starts the
    /// drive manager at power-up) and streaming, after one more tick (so that the arm's pose is
    /// measured).
    fn new(config: &'a ValidRobot, start: Option<&[f64]>) -> Result<Self, &'static str> {
        let q = start_joints(config, start)?;
        let mut manager = DriveManager::new(config, &DriveSettings::default())
            .map_err(|_| "the drive manager refused the robot")?;
        manager
            .start()
            .map_err(|_| "the drive manager did not start")?;
        let mut session = Self {
            config,
            handler: CommandHandler::new(config),
            manager,
            bus: VirtualBus::for_robot_at(config, &q),
            time: 0.0,
        };
        for _ in 0..START_TICKS {
            session.advance_bus()?;
            session.tick()?;
            if session.manager.is_operational() {
                break;
            }
        }
        if !session.manager.is_operational() {
            return Err("the drives did not become operational");
        }
        session.advance_bus()?;
        session.tick()?;
        Ok(session)
    }

    /// The simulated Whistles and bus up to the tick's time: `sim-drives` only, not part of
    /// the firmware's work on a board with real drives.
    #[inline(never)]
    fn advance_bus(&mut self) -> Result<(), &'static str> {
        self.bus
            .advance(self.time)
            .map_err(|_| "the virtual bus stalled")
    }

    /// What the firmware's control task does per tick when no request waits (the virtual bus
    /// already advanced).
    #[inline(never)]
    fn tick(&mut self) -> Result<(), &'static str> {
        self.receive();
        let measured = self.measured();
        let now = self.time;
        let out = self.core_tick(&measured)?;
        self.transmit(now, &out);
        self.drain_notices();
        Ok(())
    }

    #[inline(never)]
    fn receive(&mut self) {
        self.manager.receive(&mut self.bus);
    }

    #[inline(never)]
    fn measured(&self) -> Joints {
        self.manager.measured()
    }

    #[inline(never)]
    fn core_tick(&mut self, measured: &Joints) -> Result<StepOutput, &'static str> {
        let out = self
            .handler
            .tick(self.time, measured, &self.manager)
            .map_err(|_| "the core refused the measured joints")?;
        self.time += self.config.control_period;
        Ok(out)
    }

    #[inline(never)]
    fn transmit(&mut self, now: f64, out: &StepOutput) {
        self.manager
            .transmit(now, out.command.as_ref(), &mut self.bus);
    }

    #[inline(never)]
    fn drain_notices(&mut self) {
        while self.handler.next_notice().is_some() {}
    }

    /// Handles one request, in a measurement window; the reply must start with `expect`.
    fn request(
        &mut self,
        command: Command,
        values: [f32; VALUES],
        expect: &[u8; 2],
    ) -> Result<u32, &'static str> {
        let datagram = Request {
            command,
            values,
            index: 0,
        }
        .to_bytes();
        let (ticks, reply): (u32, [u8; MESSAGE_LEN]) =
            measure(|| self.handler.handle(&datagram, &mut self.manager));
        if reply.starts_with(expect) {
            Ok(ticks)
        } else {
            Err("a request of the move was refused")
        }
    }

    /// CM 2, GT, BG: starts the move. Returns the ticks of the three requests, the start pose
    /// and the goal as the handler decodes it.
    fn start_move(&mut self) -> Result<([u32; 3], Frame, Frame), &'static str> {
        let (_, start) = self
            .handler
            .controller()
            .measured()
            .ok_or("no measured pose")?;
        let [x, y, z]: [f64; 3] = start.translation.vector.into();
        let [roll, pitch, yaw] = math::rpy(&start.rotation);
        let goal = [
            x + OFFSET[0],
            y + OFFSET[1],
            z + OFFSET[2],
            roll,
            pitch,
            yaw + TURN,
            MIN_DURATION,
        ]
        .map(|v| v as f32);
        let mode = self.request(
            Command::ChangeMode,
            [2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            b"MC",
        )?;
        let store = self.request(Command::GoalRpy, goal, b"TG")?;
        let begin = self.request(Command::Begin, [0.0; VALUES], b"GB")?;
        let [x, y, z, roll, pitch, yaw, _] = goal.map(f64::from);
        let goal = Frame::from_parts(
            Vector3::new(x, y, z).into(),
            Rotation3::from_euler_angles(roll, pitch, yaw),
        );
        Ok(([mode, store, begin], start, goal))
    }

    fn moving(&self) -> bool {
        self.handler.controller().is_moving()
    }
}

/// The joints at `start`, or at the drives' home positions.
fn start_joints(config: &ValidRobot, start: Option<&[f64]>) -> Result<Joints, &'static str> {
    match start {
        Some(start) => Joints::from_slice(start)
            .filter(|q| q.len() == config.dof())
            .ok_or("the start has the wrong number of joints"),
        None => Ok(config.home()),
    }
}

/// Pass 1 from one start.
struct Whole {
    /// The firmware's work per tick (without the virtual bus).
    moving: Timing,
    /// The virtual bus's `advance` before each moving tick.
    bus_moving: Timing,
    holding: Timing,
    /// CM 2, GT, BG.
    requests: [u32; 3],
    pose: Timing,
    /// Motion time of the move (s).
    duration: f64,
}

/// Pass 2.
#[derive(Default)]
struct Breakdown {
    /// `manager.receive` + `manager.transmit`, one sum per tick.
    manager: Timing,
    measured: Timing,
    core_tick: Timing,
    step: Timing,
    forward: Timing,
    generator: Timing,
    workspace: Timing,
    ik: Timing,
    limiter: Timing,
    notices: Timing,
    ik_iterations: u64,
    /// Ticks in which the replica controller's command or the replica generator's set-point
    /// differed from the handler's.
    mismatches: u32,
}

/// Measures the robots of [`TICK_ROBOTS`] and prints the table; false on a failure.
pub fn run(counter: &Counter) -> bool {
    hprintln!(
        "calibration: {} nop = {} SysTick ticks -> {:.3} instructions/tick",
        Counter::calibration_instructions(),
        counter.calibration_ticks,
        counter.instructions_per_tick
    );
    hprintln!(
        "control tick: CommandHandler + DriveManager on a VirtualBus of simulated Whistles (as sim-drives) in Cartesian mode, during a straight move by ({}, {}, {}) m and {} rad yaw in >= {} s started with CM 2, GT, BG; instructions per tick, mean (max)",
        OFFSET[0],
        OFFSET[1],
        OFFSET[2],
        TURN,
        MIN_DURATION
    );
    hprintln!(
        "| robot      | part                                          | instructions/tick     | measured as                      |"
    );
    hprintln!(
        "|------------|-----------------------------------------------|-----------------------|----------------------------------|"
    );
    let mut ok = true;
    for (name, start) in TICK_ROBOTS {
        let config = ROBOTS
            .iter()
            .find(|(n, _)| *n == name)
            .and_then(|(_, bytes)| postcard::from_bytes::<RobotConfig>(bytes).ok())
            .and_then(|c| c.validate().ok());
        let Some(config) = config else {
            hprintln!("{}: not embedded, or does not decode", name);
            ok = false;
            continue;
        };
        if let Err(e) = measure_robot(name, &config, start, counter) {
            hprintln!("{}: {}", name, e);
            ok = false;
        }
    }
    ok
}

fn measure_robot(
    name: &str,
    config: &ValidRobot,
    start: &[f64],
    counter: &Counter,
) -> Result<(), &'static str> {
    let whole = whole_ticks(config, Some(start))?;
    let home = if name == HOME_ROBOT {
        Some(whole_ticks(config, None)?)
    } else {
        None
    };
    let parts = breakdown(config, start)?;
    if parts.core_tick.calls != whole.moving.calls {
        return Err("the passes did not run the same number of ticks");
    }
    let stack_used = stack_high_water(config, start)?;

    let row = |part: &str, timing: &Timing, how: &str| {
        let (mean, max) = timing.instructions(counter);
        hprintln!(
            "| {:<10} | {:<45} | {:>9.0} ({:>9.0}) | {:<32} |",
            name,
            part,
            mean,
            max,
            how
        );
    };
    let difference = |part: &str, instructions: f64, how: &str| {
        hprintln!(
            "| {:<10} | {:<45} | {:>9.0}             | {:<32} |",
            name,
            part,
            instructions,
            how
        );
    };
    let mean = |t: &Timing| t.instructions(counter).0;

    row("whole tick, moving", &whole.moving, "window per tick");
    difference(
        "whole tick + virtual bus (sim-drives board)",
        mean(&whole.moving) + mean(&whole.bus_moving),
        "the two windows per tick (means)",
    );
    row(
        "whole tick, holding after the move",
        &whole.holding,
        "window per tick",
    );
    if let Some(home) = &home {
        row(
            "whole tick, moving from home (slowed down)",
            &home.moving,
            "window per tick",
        );
    }
    row(
        "  drive manager (receive + transmit)",
        &parts.manager,
        "two windows per tick",
    );
    row("  manager.measured()", &parts.measured, "window");
    row("  handler.tick", &parts.core_tick, "window");
    row(
        "    Controller::step",
        &parts.step,
        "window, replica controller",
    );
    row(
        "      FK of the measured joints",
        &parts.forward,
        "window, Chain::forward",
    );
    row(
        "      generator: sample + commit",
        &parts.generator,
        "window, replica generator",
    );
    row(
        "      workspace: 2 x allows",
        &parts.workspace,
        "window, replica",
    );
    row(
        "      tracking IK",
        &parts.ik,
        "window, Chain::solve_tracking",
    );
    row(
        "      joint limiter: rate_ratio + limit",
        &parts.limiter,
        "window, replica",
    );
    let parts_sum = mean(&parts.forward)
        + mean(&parts.generator)
        + mean(&parts.workspace)
        + mean(&parts.ik)
        + mean(&parts.limiter);
    difference(
        "      rest of step (check, sequence, copies)",
        mean(&parts.step) - parts_sum,
        "step - the five above (means)",
    );
    difference(
        "    relay, manager.fault/is_operational",
        mean(&parts.core_tick) - mean(&parts.step),
        "handler.tick - step (means)",
    );
    row(
        "  notices: next_notice() until None",
        &parts.notices,
        "window",
    );
    row(
        "virtual bus (simulation, not on the board)",
        &whole.bus_moving,
        "window per moving tick",
    );
    let once = |ticks: u32| {
        let mut t = Timing::default();
        t.add(ticks);
        t
    };
    row(
        "request CM 2",
        &once(whole.requests[0]),
        "one handle() call",
    );
    row("request GT", &once(whole.requests[1]), "one handle() call");
    row(
        "request BG (plans the move)",
        &once(whole.requests[2]),
        "one handle() call",
    );
    row("request PS", &whole.pose, "handle(), after the move");
    hprintln!(
        "{}: {} moving ticks ({:.2} s); IK {:.2} iterations/tick; replicas off the handler in {} ticks; stack high-water of requests + ticks: {} bytes",
        name,
        whole.moving.calls,
        whole.duration,
        parts.ik_iterations as f64 / f64::from(parts.ik.calls.max(1)),
        parts.mismatches,
        stack_used
    );
    if let Some(home) = &home {
        hprintln!(
            "{}: from home the same move takes {} ticks ({:.2} s): the joint rate limits slow it down",
            name,
            home.moving.calls,
            home.duration
        );
    }
    Ok(())
}

/// Pass 1: the whole tick, one window per tick, during the move and then holding; the requests.
fn whole_ticks(config: &ValidRobot, start: Option<&[f64]>) -> Result<Whole, &'static str> {
    let mut session = Session::new(config, start)?;
    let (requests, _, _) = session.start_move()?;
    let mut moving = Timing::default();
    let mut bus_moving = Timing::default();
    while session.moving() && moving.calls < MAX_TICKS {
        let (ticks, result) = measure(|| session.advance_bus());
        result?;
        bus_moving.add(ticks);
        let (ticks, result) = measure(|| session.tick());
        result?;
        moving.add(ticks);
    }
    let mut holding = Timing::default();
    for _ in 0..HOLD_TICKS {
        session.advance_bus()?;
        let (ticks, result) = measure(|| session.tick());
        result?;
        holding.add(ticks);
    }
    let mut pose = Timing::default();
    for _ in 0..POSE_REQUESTS {
        pose.add(session.request(Command::Pose, [0.0; VALUES], b"SP")?);
    }
    Ok(Whole {
        duration: f64::from(moving.calls) * config.control_period,
        moving,
        bus_moving,
        holding,
        requests,
        pose,
    })
}

/// Pass 2: every step of the tick in a window of its own, and the replicas.
fn breakdown(config: &ValidRobot, start: &[f64]) -> Result<Breakdown, &'static str> {
    let chain = Chain::new(config);
    let limiter = JointLimiter::new(config);
    let workspace = Workspace::new(&config.workspace);
    let period = config.control_period;
    let refused = |_: KinematicsError| "the replica controller refused the measured joints";

    let mut session = Session::new(config, Some(start))?;
    // The replica starts where the handler's controller stands after the drives' start: its
    // last tick's time and measurement.
    let mut controller = Controller::new(config);
    controller
        .step(session.time - period, &session.measured())
        .map_err(refused)?;
    let (_, start_pose, goal) = session.start_move()?;
    controller
        .set_mode(Mode::Cartesian)
        .and_then(|()| controller.move_cartesian(goal, MIN_DURATION))
        .map_err(|_| "the replica controller refused the move")?;
    let mut generator = CartesianGenerator::new(
        start_pose,
        config.cartesian.max_velocity,
        config.cartesian.max_acceleration,
    );
    generator
        .move_to(goal, MIN_DURATION)
        .map_err(|_| "the replica generator refused the move")?;

    let mut parts = Breakdown::default();
    while session.moving() && parts.core_tick.calls < MAX_TICKS {
        let time = session.time;
        let last_command = session.handler.controller().command();

        session.advance_bus()?;
        let (receive, ()) = measure(|| session.receive());
        let (ticks, measured) = measure(|| session.measured());
        parts.measured.add(ticks);
        let (ticks, out) = measure(|| session.core_tick(&measured));
        parts.core_tick.add(ticks);
        let out = out?;
        let (transmit, ()) = measure(|| session.transmit(time, &out));
        parts.manager.add(receive + transmit);
        let (ticks, ()) = measure(|| session.drain_notices());
        parts.notices.add(ticks);

        // Replicas, with the tick's inputs.
        let (ticks, replica) = measure(|| controller.step(time, &measured));
        parts.step.add(ticks);
        let replica = replica.map_err(refused)?;
        let (ticks, pose) = measure(|| chain.forward(&measured));
        parts.forward.add(ticks);
        let pose = pose.map_err(|_| "FK refused the measured joints")?;
        let (ticks, (setpoint, _)) = measure(|| {
            let t = generator.elapsed() + period;
            let sample = generator.sample(t);
            generator.commit(t, sample);
            sample
        });
        parts.generator.add(ticks);
        if replica.command != out.command || out.setpoint != Some(setpoint) {
            parts.mismatches += 1;
        }
        let (ticks, _) = measure(|| {
            workspace.allows(&pose.translation.vector)
                && workspace.allows(&setpoint.translation.vector)
        });
        parts.workspace.add(ticks);
        // The set-point the tick's IK solved for, from the tick's seed.
        let target = out.setpoint.unwrap_or(setpoint);
        let seed = last_command.unwrap_or(measured);
        let (ticks, solved) = measure(|| chain.solve_tracking(&target, &seed, &config.ik));
        parts.ik.add(ticks);
        let solved = solved.map_err(|_| "the replica IK refused")?;
        let solution = solved.solution();
        parts.ik_iterations += u64::from(solution.iterations);
        let (ticks, _) = measure(|| {
            let ratio = limiter.rate_ratio(&solution.q, &seed);
            (ratio, limiter.limit(&solution.q, &seed))
        });
        parts.limiter.add(ticks);
    }
    Ok(parts)
}

/// Pass 3: the stack the requests and ticks of the move need, below this function's frame.
fn stack_high_water(config: &ValidRobot, start: &[f64]) -> Result<usize, &'static str> {
    // The session (with the ≈ 24 KB virtual bus, a static in the firmware) and the drives'
    // start before the painting: only the control work is measured.
    let mut session = Session::new(config, Some(start))?;
    let base = stack::pointer();
    let painted = stack::paint(base, STACK_DEPTH);
    session.start_move()?;
    for _ in 0..MAX_TICKS {
        if !session.moving() {
            break;
        }
        session.advance_bus()?;
        session.tick()?;
    }
    Ok(stack::high_water(&painted))
}
