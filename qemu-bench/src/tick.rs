//! One full control tick of the core, as the firmware runs it: the core's [`Cycle`] — the
//! command handler and the CANopen drive manager — on a [`VirtualBus`] of simulated Whistles
//! (the firmware's `sim-drives` build), in Cartesian mode, during a straight-line move started
//! with datagrams (`CM 2`, `GT`, `BG`), on the robots of [`TICK_ROBOTS`]. The drives start (NMT,
//! configuration, PT initialisation) before the move, as at the firmware's power-up.
//!
//! Nothing here re-implements the tick: every window is around [`Cycle::tick`], the call the
//! firmware's control task makes.
//!
//! 1. **Whole tick**: one window per tick around `Cycle::tick` with no request waiting. The
//!    virtual bus's `advance` (the simulated Whistles and the bus: on a board with real drives,
//!    the drives and the FDCAN peripheral) runs before it, in a window of its own
//!    ([`BenchBus`] keeps it out of the tick's window).
//! 2. **Requests**: the ticks that carry `CM 2`, `GT`, `BG` and `PS` (one request waiting in
//!    the link), whole.
//! 3. **Stack**: the stack is painted below the caller, the move runs again, and the lowest
//!    word written gives the stack the control work needs.
//! 4. **Signing** ([`signing`]): one signature check and one signing on their own, and the
//!    tick that carries a signed `PS` (checked, answered signed) with a key set; one write of
//!    the replay reservation to the flash log (on sectors in RAM).
//! 5. **Planning burst** ([`planning`]), on every embedded robot: eight planning requests to
//!    unreachable goals in one tick, served one a tick; the worst of those ticks, also as a
//!    share of the control period at 480 MHz ([`BOARD_HZ`], one instruction a cycle assumed).

use core::f64::consts::FRAC_PI_2;

use armgate_core::config::{RobotConfig, ValidRobot};
use armgate_core::cycle::{CanDrives, Cycle, Datagram, Dropped, Link, Outgoing, Signing};
use armgate_core::drives::{BusState, CanBus, DriveSettings, TxError};
use armgate_core::kinematics::Joints;
use armgate_core::math;
use armgate_core::sim::VirtualBus;
use armgate_protocol::can::CanFrame;
use armgate_protocol::client::{Command, Request, VALUES};
use cortex_m_semihosting::hprintln;

use crate::counter::{Counter, Timing, measure};
use crate::stack;

mod planning;
mod signing;
mod twist;

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
/// Upper bound on the ticks of the move (78 s at ranger-mk1's period: from its home pose the
/// line check now plans the move for about 57 s, as slow as joint 1 needs it, issue 33).
const MAX_TICKS: u32 = 4_000;
/// Ticks a planning request's answer may take (its work in slices).
const MAX_PLANNING_TICKS: u32 = 1_000;
/// Ticks measured after the move, the arm holding in Cartesian mode.
const HOLD_TICKS: u32 = 50;
/// PS requests measured after the move.
const POSE_REQUESTS: u32 = 20;
/// Ticks the drives may take to start (12 with drives already in position mode).
const START_TICKS: u32 = 100;
/// The board's core clock (STM32H743), for the planning burst's share of the period.
const BOARD_HZ: f64 = 480e6;
/// Stack painted below the caller for the high-water mark (bytes).
const STACK_DEPTH: usize = 32 * 1024;

/// The virtual bus, advanced by the benchmark outside the tick's window (the firmware's cycle
/// advances it inside `Cycle::tick`, through [`CanBus::advance_to`]).
struct BenchBus(VirtualBus);

impl CanBus for BenchBus {
    fn try_transmit(&mut self, frame: &CanFrame) -> Result<(), TxError> {
        self.0.try_transmit(frame)
    }

    fn try_receive(&mut self) -> Option<CanFrame> {
        self.0.try_receive()
    }

    fn state(&self) -> BusState {
        self.0.state()
    }
}

/// The client port: at most one request waiting; the last answer kept.
#[derive(Default)]
struct BenchLink {
    waiting: Option<Datagram<()>>,
    answer: Option<Datagram<()>>,
}

impl Link<()> for BenchLink {
    fn receive(&mut self) -> Option<Datagram<()>> {
        self.waiting.take()
    }

    fn send(&mut self, datagram: &Datagram<()>, kind: Outgoing) -> Result<(), Dropped> {
        if kind == Outgoing::Reply {
            self.answer = Some(*datagram);
        }
        Ok(())
    }
}

/// The firmware's control state with `sim-drives`.
struct Session {
    cycle: Cycle<CanDrives<BenchBus>, ()>,
    link: BenchLink,
}

impl Session {
    /// The drives at `start` (or at their home positions), started (the firmware starts the
    /// drive manager at power-up) and streaming, after one more tick (so that the arm's pose is
    /// measured).
    fn new(config: &ValidRobot, start: Option<&[f64]>) -> Result<Self, &'static str> {
        Self::with_signing(config, start, Signing::default())
    }

    /// The same, checking signatures as `signing` says.
    fn with_signing(
        config: &ValidRobot,
        start: Option<&[f64]>,
        signing: Signing,
    ) -> Result<Self, &'static str> {
        let q = start_joints(config, start)?;
        let bus = BenchBus(VirtualBus::for_robot_at(config, &q));
        let drives = CanDrives::started(config, &DriveSettings::default(), bus)
            .map_err(|_| "the drive manager refused the robot")?;
        let mut session = Self {
            cycle: Cycle::new(config, drives).with_signing(signing),
            link: BenchLink::default(),
        };
        for _ in 0..START_TICKS {
            session.advance_bus()?;
            session.tick();
            if session.cycle.drives().manager().is_operational() {
                break;
            }
        }
        if !session.cycle.drives().manager().is_operational() {
            return Err("the drives did not become operational");
        }
        session.advance_bus()?;
        session.tick();
        Ok(session)
    }

    /// The simulated Whistles and bus up to the next tick's time: `sim-drives` only, not part
    /// of the firmware's work on a board with real drives.
    #[inline(never)]
    fn advance_bus(&mut self) -> Result<(), &'static str> {
        let due = self.cycle.next_due_us() as f64 * 1e-6;
        self.cycle
            .drives_mut()
            .bus_mut()
            .0
            .advance(due)
            .map_err(|_| "the virtual bus stalled")
    }

    /// The firmware's control tick, on time.
    #[inline(never)]
    fn tick(&mut self) {
        let now = self.cycle.next_due_us();
        self.cycle.tick(now, &mut self.link);
    }

    /// One tick that carries a request, in a measurement window (the bus advanced before it);
    /// the reply must start with `expect`. A planning request answered ticks later (its work
    /// in slices) gives the ticks that carried it and the later ones until the answer.
    fn request(
        &mut self,
        command: Command,
        values: [f32; VALUES],
        expect: &[u8; 2],
    ) -> Result<(u32, Timing), &'static str> {
        let datagram = Request {
            command,
            values,
            index: 0,
        }
        .to_bytes();
        self.exchange(&datagram, expect)
    }

    /// The tick that carries `datagram` and those after it until its answer, each in a
    /// measurement window; the reply must start with `expect`.
    fn exchange(
        &mut self,
        datagram: &[u8],
        expect: &[u8; 2],
    ) -> Result<(u32, Timing), &'static str> {
        self.advance_bus()?;
        self.link.waiting = Some(Datagram::new(datagram, ()));
        self.link.answer = None;
        let (first, ()) = measure(|| self.tick());
        let mut later = Timing::default();
        while self.link.answer.is_none() && later.calls < MAX_PLANNING_TICKS {
            self.advance_bus()?;
            let (ticks, ()) = measure(|| self.tick());
            later.add(ticks);
        }
        match self.link.answer {
            Some(reply) if reply.payload().starts_with(expect) => Ok((first, later)),
            answer => {
                // What it was answered instead, for the reader of the failure.
                let payload = answer.as_ref().map_or(&[][..], |reply| reply.payload());
                let end = payload.iter().position(|&b| b == 0).unwrap_or(payload.len());
                let text = payload.get(..end.min(30)).unwrap_or_default();
                hprintln!("answered {:?}", core::str::from_utf8(text).unwrap_or("(not text)"));
                Err("a request of the move was refused")
            }
        }
    }

    /// CM 2, GT, BG: starts the move. Returns the ticks that carried the three requests, and
    /// those of the BG's line check after its first (answered when the check ends).
    fn start_move(&mut self) -> Result<([u32; 3], Timing), &'static str> {
        let (_, start) = self
            .cycle
            .handler()
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
        let (mode, _) = self.request(
            Command::ChangeMode,
            [2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            b"MC",
        )?;
        let (store, _) = self.request(Command::GoalRpy, goal, b"TG")?;
        let (begin, check) = self.request(Command::Begin, [0.0; VALUES], b"GB")?;
        Ok(([mode, store, begin], check))
    }

    fn moving(&self) -> bool {
        self.cycle.handler().controller().is_moving()
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

/// One move from one start.
struct Whole {
    /// The firmware's work per tick (without the virtual bus).
    moving: Timing,
    /// The virtual bus's `advance` before each moving tick.
    bus_moving: Timing,
    holding: Timing,
    /// The ticks that carried CM 2, GT, BG.
    requests: [u32; 3],
    /// The ticks after the BG's until its answer: its line check, a slice a tick.
    check: Timing,
    /// Ticks that carried a PS, after the move.
    pose: Timing,
    /// Ticks that carried a TW, streaming after the move.
    twist: Timing,
    /// Motion time of the move (s).
    duration: f64,
}

/// Measures the robots of [`TICK_ROBOTS`] and prints the table; false on a failure.
pub fn run(counter: &Counter) -> bool {
    counter.print_calibration();
    hprintln!(
        "control tick: Cycle::tick (CommandHandler + DriveManager) on a VirtualBus of simulated Whistles (as sim-drives) in Cartesian mode, during a straight move by ({}, {}, {}) m and {} rad yaw in >= {} s started with CM 2, GT, BG; instructions per tick, mean (max)",
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
    bursts(counter) && ok
}

/// The planning burst ([`planning`]) on every embedded robot, from its start in
/// [`TICK_ROBOTS`] or else its home pose; prints the table; false on a failure.
fn bursts(counter: &Counter) -> bool {
    hprintln!();
    hprintln!(
        "planning burst: 8 planning requests to unreachable goals in one tick (Cartesian mode: GT, BG, BG, BG to goal 1, the same to goal 2), served one a tick; worst tick, also as a share of the control period at 480 MHz (1 instruction a cycle assumed; goal <= 50 %)"
    );
    hprintln!(
        "| robot              | goal 1 (m)           | goal 2 (m)           | first BG to goal 1; goal 2                                      | worst tick (mean)     | period   | share  |"
    );
    hprintln!(
        "|--------------------|----------------------|----------------------|-----------------------------------------------------------------|-----------------------|----------|--------|"
    );
    let mut ok = true;
    for (name, bytes) in ROBOTS {
        let Some(config) = postcard::from_bytes::<RobotConfig>(bytes)
            .ok()
            .and_then(|c| c.validate().ok())
        else {
            hprintln!("{}: does not decode", name);
            ok = false;
            continue;
        };
        let start = TICK_ROBOTS
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, start)| *start);
        let burst = Session::new(&config, start)
            .and_then(|mut session| planning::burst_ticks(&mut session, &config));
        let burst = match burst {
            Ok(burst) => burst,
            Err(e) => {
                hprintln!("{}: planning burst: {}", name, e);
                ok = false;
                continue;
            }
        };
        let (mean, max) = burst.timing.instructions(counter);
        let text = |k: usize| {
            let bytes = burst.refusals.get(k).map_or(&[][..], |b| &b[..]);
            let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
            core::str::from_utf8(bytes.get(..end).unwrap_or_default()).unwrap_or("(not text)")
        };
        let [g1, g2] = burst.goals;
        hprintln!(
            "| {:<18} | {:>6.3} {:>6.3} {:>6.3} | {:>6.3} {:>6.3} {:>6.3} | {:<30}; {:<32} | {:>9.0} ({:>9.0}) | {:>5.2} ms | {:>5.1} % |",
            name,
            g1[0],
            g1[1],
            g1[2],
            g2[0],
            g2[1],
            g2[2],
            text(0),
            text(1),
            max,
            mean,
            config.control_period * 1e3,
            100.0 * max / (config.control_period * BOARD_HZ)
        );
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
    let stopping = stopping_ticks(config, start, whole.moving.calls / 2)?;
    let home = if name == HOME_ROBOT {
        Some(whole_ticks(config, None)?)
    } else {
        None
    };
    let stack_used = stack_high_water(config, start)?;
    let signing = signing::costs(config, Some(start))?;

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
    let mean = |t: &Timing| t.instructions(counter).0;
    let once = |ticks: u32| {
        let mut t = Timing::default();
        t.add(ticks);
        t
    };

    row("whole tick, moving", &whole.moving, "window per tick");
    hprintln!(
        "| {:<10} | {:<45} | {:>9.0}             | {:<32} |",
        name,
        "whole tick + virtual bus (sim-drives board)",
        mean(&whole.moving) + mean(&whole.bus_moving),
        "the two windows per tick (means)"
    );
    row(
        "whole tick, stopping (ST halfway, along the line)",
        &stopping,
        "window per tick",
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
        "virtual bus (simulation, not on the board)",
        &whole.bus_moving,
        "window per moving tick",
    );
    row(
        "tick with request CM 2",
        &once(whole.requests[0]),
        "one tick",
    );
    row("tick with request GT", &once(whole.requests[1]), "one tick");
    row(
        "tick with request BG (its line check's 1st slice)",
        &once(whole.requests[2]),
        "one tick",
    );
    row(
        "ticks of the BG's line check after its 1st",
        &whole.check,
        "window per tick",
    );
    row(
        "tick with request PS, holding",
        &whole.pose,
        "window per tick",
    );
    row(
        "tick with request TW, streaming a twist",
        &whole.twist,
        "window per tick",
    );
    row(
        "signature check of one datagram (goal 20,000)",
        &signing.verify,
        "window per check",
    );
    row(
        "signing one answer",
        &signing.sign,
        "window per signing",
    );
    row(
        "tick with signed PS, holding (key set)",
        &signing.pose,
        "window per tick",
    );
    row(
        "reservation kept (flash log, RAM): once per 2 s",
        &signing.keep,
        "window per write",
    );
    hprintln!(
        "{}: {} moving ticks ({:.2} s); stack high-water of requests + ticks: {} bytes",
        name,
        whole.moving.calls,
        whole.duration,
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

/// The whole tick, one window per tick, during the move and then holding; the requests.
fn whole_ticks(config: &ValidRobot, start: Option<&[f64]>) -> Result<Whole, &'static str> {
    let mut session = Session::new(config, start)?;
    let (requests, check) = session.start_move()?;
    let mut moving = Timing::default();
    let mut bus_moving = Timing::default();
    while session.moving() && moving.calls < MAX_TICKS {
        let (ticks, result) = measure(|| session.advance_bus());
        result?;
        bus_moving.add(ticks);
        let (ticks, ()) = measure(|| session.tick());
        moving.add(ticks);
    }
    let mut holding = Timing::default();
    for _ in 0..HOLD_TICKS {
        session.advance_bus()?;
        let (ticks, ()) = measure(|| session.tick());
        holding.add(ticks);
    }
    let mut pose = Timing::default();
    for _ in 0..POSE_REQUESTS {
        pose.add(session.request(Command::Pose, [0.0; VALUES], b"SP")?.0);
    }
    let twist = twist::streaming_ticks(&mut session)?;
    Ok(Whole {
        duration: f64::from(moving.calls) * config.control_period,
        moving,
        bus_moving,
        holding,
        requests,
        check,
        pose,
        twist,
    })
}

/// The whole tick while the supervisor stops the move along its line: `ST` after `after`
/// moving ticks, then one window per tick until the arm is at rest.
fn stopping_ticks(config: &ValidRobot, start: &[f64], after: u32) -> Result<Timing, &'static str> {
    let mut session = Session::new(config, Some(start))?;
    session.start_move()?;
    for _ in 0..after {
        session.advance_bus()?;
        session.tick();
    }
    session.request(Command::Stop, [0.0; VALUES], b"TS")?;
    let mut stopping = Timing::default();
    while session.moving() && stopping.calls < MAX_TICKS {
        session.advance_bus()?;
        let (ticks, ()) = measure(|| session.tick());
        stopping.add(ticks);
    }
    Ok(stopping)
}

/// The stack the requests and ticks of the move need, below this function's frame.
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
        session.tick();
    }
    Ok(stack::high_water(&painted))
}
