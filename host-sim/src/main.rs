//! `armgate-sim`: the armgate controller core on this computer, with a simulated arm.
//!
//! It runs the same core as the firmware: the control tick at the robot's period, and the
//! 31-byte UDP command protocol. Only bytes and time are handled here.

mod args;
mod backend;
mod log;
mod pcap;
mod record;
mod robots;
mod status;
mod udp;
mod whistles;

use std::io::IsTerminal;
use std::net::{SocketAddr, UdpSocket};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use armgate_core::command::Network;
use armgate_core::config::SAMPLE_TIME;
use armgate_core::config::{Streaming, ValidRobot};
use armgate_core::cycle::{Cycle, DriveSide, Signing, StateFile, UnsignedAccess};
use armgate_core::kinematics::{Chain, Joints};
use armgate_core::math::{self, Quaternion};
use armgate_core::sim::ArmModel;
use armgate_core::sim::replay::{self, Replay};
use armgate_core::sim::{IdealArm, RateLimitedArm};
use armgate_protocol::client::signed::{ControllerId, read_key_file};
use backend::{Backend, CanChoice};
use clap::{Parser, ValueEnum};
use log::{Logger, Record, Tick};
use udp::{Inbox, Stats, UdpLink};

/// Run the armgate arm controller on this computer, with a simulated arm.
///
/// Clients command it with 31-byte UDP datagrams (docs/protocol.md), for example with the
/// `armgate` client: `armgate mode cart`, `armgate move 0.1 0.6 0.9 0 1.57 0`, `armgate pose`.
/// Only addresses on the allow-list may command the arm: anyone else on the network could move
/// it. Stop with Ctrl-C.
#[derive(Parser, Debug)]
#[command(version, about, long_about)]
struct Args {
    /// Robot description file (TOML); see docs/robot-file.md. A shipped robot's name
    /// (`ur5`, `robots/ur5.toml`) that is not a file here loads its built-in copy.
    #[arg(long, default_value = "robots/ranger-mk1.toml")]
    robot: PathBuf,
    /// UDP address to listen on for client commands.
    #[arg(long, default_value = "127.0.0.1:7031")]
    listen: SocketAddr,
    /// Networks allowed to send commands besides loopback (127.0.0.0/8 and ::1, always
    /// allowed), e.g. 192.168.1.0/24 (repeatable). Datagrams from elsewhere are dropped and
    /// counted.
    #[arg(long = "allow", value_name = "NETWORK")]
    allow: Vec<Network>,
    /// The signing key file (64 hex digits on one line; docs/safety.md, "Signing"): only
    /// datagrams signed with it are served, the rest dropped and counted.
    #[arg(long, value_name = "FILE")]
    key: Option<PathBuf>,
    /// With --key: what unsigned datagrams may do: `no` (dropped), `read` (PS, jP, TM, SQ and
    /// the stops ST, jR) or `all` (a lab moving its clients to signing).
    #[arg(
        long,
        default_value = "no",
        value_name = "no|read|all",
        requires = "key"
    )]
    allow_unsigned: UnsignedAccess,
    /// With --key: this controller's id, 8 hex digits, covered by every signature (a key shared
    /// by two arms moves only the one addressed). Default: derived from the robot file's name
    /// and the address listened on (printed at start).
    #[arg(long, value_name = "HEX", requires = "key")]
    controller_id: Option<ControllerId>,
    /// With --key: the replay state file, which keeps the newest signed timestamp served across
    /// restarts (written at most once per 2 s of signed use). Default:
    /// $XDG_STATE_HOME/armgate/replay-<controller id> ($HOME/.local/state/... without it).
    #[arg(long, value_name = "FILE", requires = "key")]
    state: Option<PathBuf>,
    /// Where set-points go: `sim` = one simulated Elmo Whistle per drive of the robot file on
    /// a virtual CAN bus; `socketcan:IFACE` = real drives through Linux SocketCAN (e.g.
    /// socketcan:can0); `off` = no drives, a simulated arm (see --arm).
    #[arg(long, default_value = "sim", value_name = "sim|socketcan:IFACE|off")]
    can: CanChoice,
    /// With --can socketcan:IFACE: write frames no faster than the robot file's bit rate
    /// carries them, for a bus without bit timing (vcan, QEMU's emulated CAN bus), where a
    /// cycle's burst would arrive at once and overrun the receiver (docs/drives.md).
    #[arg(long)]
    pace_can: bool,
    /// With --can off: how the simulated joints follow the commands.
    #[arg(long, value_enum, default_value_t = ArmKind::Ideal)]
    arm: ArmKind,
    /// Overrides the robot file's `drives.streaming`: `interpreter` (QP writes and queries) or
    /// `pdo` (SYNC, one receive and one transmit PDO per drive and cycle; docs/drives.md).
    #[arg(long, value_enum, value_name = "interpreter|pdo")]
    streaming: Option<StreamingChoice>,
    /// Overrides the robot file's `control_period` with this many 360 µs drive samples (e.g.
    /// 12 = 4.32 ms, the PDO schedule's fastest for six drives at 500 kbit/s); the bus-load
    /// check still applies.
    #[arg(long, value_name = "N")]
    period_samples: Option<u16>,
    /// Starting joint positions, comma-separated, within the joint limits (default: the drives'
    /// home positions).
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        value_name = "Q1,Q2,.."
    )]
    start: Option<Vec<f64>>,
    /// Write CSV logs (commands, replies, warnings, state) into this directory.
    #[arg(long, value_name = "DIR")]
    log_dir: Option<PathBuf>,
    /// Capture the client's UDP datagrams and every CAN frame into this pcapng file (for
    /// Wireshark with tools/wireshark/armgate.lua).
    #[arg(long, value_name = "FILE")]
    pcap: Option<PathBuf>,
    /// Record the run into this MCAP file for Foxglove (docs/visualisation.md): joints,
    /// frames, goals and planned paths, the workspace, every request, reply and notice, the
    /// raw datagrams and CAN frames, and the URDF; simulation time as log time.
    #[arg(long, value_name = "FILE")]
    mcap: Option<PathBuf>,
    /// Serve the same channels live over the Foxglove WebSocket protocol (Foxglove: Open
    /// connection, ws://ADDR), on 127.0.0.1:8765 without ADDR. Read-only: a viewer cannot
    /// command the arm; mind who can reach ADDR all the same.
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = "127.0.0.1:8765")]
    foxglove: Option<SocketAddr>,
    /// Exit after this many seconds (default: run until Ctrl-C or SIGTERM).
    #[arg(long, value_name = "SECONDS", value_parser = args::parse_seconds)]
    duration: Option<f64>,
    /// No status line on the terminal.
    #[arg(long)]
    quiet: bool,
    /// Be the other side of the bus instead of the controller: the robot file's simulated
    /// Whistles on the interface of `--can socketcan:IFACE` (with `--start`, `--streaming`,
    /// `--duration`), for a controller on a second adapter or the same vcan. Faults are
    /// injected on standard input: `emcy NODE`, `heartbeat-lost NODE`, `silent NODE`.
    #[arg(long)]
    whistles: bool,
    /// Print the arm's pose at its home position and exit.
    #[arg(long)]
    print_home: bool,
    /// Replay a recorded exchange (docs/architecture.md) on a virtual clock for this many ticks
    /// instead of serving UDP, and print the transcript: what the firmware on Linux must match.
    #[arg(long, value_names = ["FILE", "TICKS"], num_args = 2, hide = true)]
    replay: Option<Vec<String>>,
}

/// `--streaming`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum StreamingChoice {
    /// The binary interpreter: a QP write and a query per drive and cycle.
    Interpreter,
    /// Process data: SYNC, a receive and a transmit PDO per drive and cycle.
    Pdo,
}

/// The robot file with the `--streaming` and `--period-samples` overrides, validated again.
fn with_overrides(config: ValidRobot, args: &Args) -> Result<ValidRobot, String> {
    if args.streaming.is_none() && args.period_samples.is_none() {
        return Ok(config);
    }
    config
        .edit(|config| {
            match args.streaming {
                Some(StreamingChoice::Interpreter) => {
                    config.drives.streaming = Streaming::Interpreter;
                }
                Some(StreamingChoice::Pdo) => config.drives.streaming = Streaming::Pdo,
                None => {}
            }
            if let Some(samples) = args.period_samples {
                config.control_period = f64::from(samples) * SAMPLE_TIME;
            }
        })
        .map_err(|e| format!("--streaming/--period-samples: {e}"))
}

/// The simulated arm's dynamics.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum ArmKind {
    /// Joints reach every command at once.
    Ideal,
    /// Joints follow with the robot file's joint velocity and acceleration limits.
    RateLimited,
}

fn main() -> ExitCode {
    let args = Args::parse();
    let config = match robots::load(&args.robot).and_then(|config| with_overrides(config, &args)) {
        Ok(config) => config,
        Err(e) => {
            eprintln!("armgate-sim: {}: {e}", args.robot.display());
            return ExitCode::FAILURE;
        }
    };
    if args.print_home {
        print_home(&config);
        return ExitCode::SUCCESS;
    }
    match run(&args, &config) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("armgate-sim: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(args: &Args, config: &ValidRobot) -> Result<(), String> {
    let n = config.dof();
    let start = args::start_joints(config, args.start.as_deref()).map_err(|e| {
        let what = if args.start.is_some() {
            "--start"
        } else {
            "home"
        };
        format!("{what}: {e}")
    })?;
    if args.whistles {
        return serve_whistles(args, config, &start);
    }
    let drives = Backend::open(&args.can, args.pace_can, config, &start, || {
        arm_model(args.arm, config, start)
    })?;
    let describe = drives.describe();
    if let Some(replay) = &args.replay {
        return replay_exchange(config, drives, replay);
    }
    let socket = bind(args.listen).map_err(|e| format!("{}: {e}", args.listen))?;
    let local = socket.local_addr().map_err(|e| e.to_string())?;
    let (signing, store) = signing(args, local)?;
    let signing_note = match (&signing.key, &store) {
        (Some(key), Some(store)) => format!(
            ", signing key set for controller {} (unsigned: {}; replay state {})",
            key.controller(),
            signing.unsigned,
            store.path().display()
        ),
        _ => String::new(),
    };
    let mut cycle: SimCycle = Cycle::new(config, drives)
        .with_store(store)
        .with_signing(signing);
    let allow = args::allow_list(&args.allow);
    let logger = match &args.log_dir {
        Some(dir) => Logger::start(dir, n).map_err(|e| format!("{}: {e}", dir.display()))?,
        None => Logger::disabled(),
    };
    let capture = match &args.pcap {
        Some(path) => {
            Some(pcap::Capture::start(path).map_err(|e| format!("{}: {e}", path.display()))?)
        }
        None => None,
    };
    let recording = if args.mcap.is_some() || args.foxglove.is_some() {
        let (recording, live) =
            record::Recording::start(config, args.mcap.as_deref(), args.foxglove)
                .map_err(|e| e.to_string())?;
        if let Some(addr) = live {
            eprintln!("armgate-sim: Foxglove live view on ws://{addr}");
        }
        Some(recording)
    } else {
        None
    };
    socket
        .set_nonblocking(true)
        .map_err(|e| format!("{}: {e}", args.listen))?;
    let running = Arc::new(AtomicBool::new(true));
    let stop = running.clone();
    // Ctrl-C, and SIGTERM as well (the `termination` feature): the logs are flushed either way.
    ctrlc::set_handler(move || stop.store(false, Ordering::SeqCst))
        .map_err(|e| format!("Ctrl-C handler: {e}"))?;
    let allowed: Vec<String> = allow.iter().map(ToString::to_string).collect();
    eprintln!(
        "armgate-sim: {} ({n} joints, {:.2} ms period, drives: {describe}) on udp://{}, allowing {}{signing_note}",
        config.name,
        config.control_period * 1e3,
        socket.local_addr().map_err(|e| e.to_string())?,
        allowed.join(", ")
    );

    let status = !args.quiet && std::io::stderr().is_terminal();
    let epoch = Instant::now();
    let mut next_status = epoch;
    let mut stats = Stats::default();
    let mut inbox = Inbox::default();
    while running.load(Ordering::SeqCst) {
        let now = Instant::now();
        let elapsed = now - epoch;
        if args.duration.is_some_and(|d| elapsed.as_secs_f64() >= d) {
            break;
        }
        let due = Duration::from_micros(cycle.next_due_us());
        if elapsed < due {
            // A sleep is precise; socket timeouts are rounded to the kernel's tick.
            std::thread::sleep(due - elapsed);
            continue;
        }
        // The cycle's policy (docs/architecture.md): requests are answered at the start of
        // the next tick, late ticks are caught up back to back, the core's time is the
        // schedule's.
        let mut link = UdpLink {
            socket: &socket,
            local,
            allow: &allow,
            inbox: &mut inbox,
            holder: cycle.holder().map(|holder| holder.ip()),
            ahead_taken: 0,
            logger: &logger,
            stats: &mut stats,
            time: elapsed.as_secs_f64(),
            error: None,
        };
        record::set_time(cycle.next_due_us());
        let outcome = cycle.tick(micros(elapsed), &mut link);
        if let Some(error) = link.error {
            return Err(error);
        }
        if let Some(error) = cycle.store_mut().as_mut().and_then(StateFile::take_error) {
            eprintln!(
                "armgate-sim: replay state not kept: {error} (a restart could serve replays)"
            );
        }
        if logger.enabled()
            && let Ok(out) = outcome.step
        {
            logger.log(Record::Tick(Box::new(Tick {
                t: outcome.time,
                mode: cycle.handler().controller().mode().name(),
                pose: out.measured_pose,
                joints: cycle.drives().measured(),
                command: out.command,
                setpoint: out.setpoint,
            })));
        }
        if record::enabled()
            && let Ok(out) = &outcome.step
        {
            record::joints(
                outcome.time,
                cycle.drives().measured(),
                out.command,
                out.setpoint,
                out.measured_pose,
            );
        }
        if status && now >= next_status {
            next_status = now + Duration::from_millis(250);
            eprint!("\r{}\x1b[K", status::line(&cycle, &stats, &logger));
        }
    }
    if status {
        eprintln!();
    }
    let dropped = logger.dropped();
    logger.finish().map_err(|e| format!("log: {e}"))?;
    if let (Some(capture), Some(path)) = (capture, &args.pcap) {
        let (written, lost) = capture
            .finish()
            .map_err(|e| format!("{}: {e}", path.display()))?;
        eprintln!(
            "armgate-sim: {}: {written} packets captured, {lost} dropped (queue full)",
            path.display()
        );
    }
    if let Some(recording) = recording {
        let dropped = record::dropped();
        let (written, _) = recording.finish().map_err(|e| format!("record: {e}"))?;
        eprintln!(
            "armgate-sim: recorded {written} messages, {dropped} events dropped (queue full)"
        );
    }
    let counters = cycle.counters();
    eprintln!(
        "armgate-sim: stopped; {}",
        status::summary(&stats, status::snapshot(&cycle).refused, &counters, dropped)
    );
    eprintln!("armgate-sim: {}", status::signing(&cycle.signing()));
    if let Some(summary) = cycle.drives().socketcan_summary() {
        eprintln!("armgate-sim: {summary}");
    }
    Ok(())
}

/// `--whistles`: the simulated Whistles on the `--can` interface until Ctrl-C, SIGTERM or
/// `--duration`.
fn serve_whistles(args: &Args, config: &ValidRobot, start: &Joints) -> Result<(), String> {
    let CanChoice::SocketCan(iface) = &args.can else {
        return Err("--whistles needs --can socketcan:IFACE".into());
    };
    let running = Arc::new(AtomicBool::new(true));
    let stop = running.clone();
    ctrlc::set_handler(move || stop.store(false, Ordering::SeqCst))
        .map_err(|e| format!("Ctrl-C handler: {e}"))?;
    whistles::serve(
        config,
        start,
        (iface, args.pace_can),
        args.duration,
        &running,
    )
}

/// `--key`, `--allow-unsigned`, `--controller-id` (default from the robot file's name and
/// `local`, the address listened on) and `--state`.
fn signing(args: &Args, local: SocketAddr) -> Result<(Signing, Option<StateFile>), String> {
    let Some(path) = &args.key else {
        return Ok((Signing::default(), None));
    };
    let key = read_key_file(path).map_err(|e| format!("--key {e}"))?;
    let robot = args.robot.file_name().unwrap_or_default().to_string_lossy();
    let controller = args
        .controller_id
        .unwrap_or_else(|| ControllerId::derive(&[&robot, &local.to_string()]));
    let state = args
        .state
        .clone()
        .unwrap_or_else(|| StateFile::default_path(controller));
    let store = StateFile::open(&state).map_err(|e| format!("--state {e}"))?;
    let signing = Signing {
        key: Some(key.for_controller(controller)),
        unsigned: args.allow_unsigned,
    };
    Ok((signing, Some(store)))
}

/// The cycle `armgate-sim` runs: its replay store a state file when it has a key.
pub type SimCycle = Cycle<Backend, SocketAddr, Option<StateFile>>;

/// `--replay FILE TICKS`: the cycle as `run` builds it, on the recorded exchange.
fn replay_exchange(config: &ValidRobot, drives: Backend, replay: &[String]) -> Result<(), String> {
    let [file, ticks] = replay else {
        return Err("--replay takes FILE TICKS".into());
    };
    let ticks: u64 = ticks
        .parse()
        .map_err(|e| format!("--replay {ticks}: {e}"))?;
    let text = std::fs::read_to_string(file).map_err(|e| format!("{file}: {e}"))?;
    let recording = Replay::parse(&text).map_err(|e| format!("{file}: {e}"))?;
    let mut cycle: Cycle<Backend, ()> = Cycle::new(config, drives);
    let transcript = recording.run(&mut cycle, ticks, |drives| match drives {
        Backend::Can(can) => match &can.bus().0 {
            armgate_socketcan::LinuxBus::Simulated(bus) => replay::can_drives(can.manager(), bus),
            armgate_socketcan::LinuxBus::SocketCan(_) => "SocketCAN".into(),
        },
        Backend::Direct(_) => "simulated arm".into(),
    });
    print!("{transcript}");
    Ok(())
}

/// Whole microseconds of `d` (saturating).
fn micros(d: Duration) -> u64 {
    u64::try_from(d.as_micros()).unwrap_or(u64::MAX)
}

/// Receive buffer asked of the kernel: about 4,000 queued datagrams, so that a burst from a
/// client is not dropped while a tick runs (the kernel caps it at `net.core.rmem_max`).
const RECEIVE_BUFFER: usize = 4 << 20;

/// A UDP socket on `addr` with a large receive buffer.
fn bind(addr: SocketAddr) -> std::io::Result<UdpSocket> {
    use socket2::{Domain, Protocol, Socket, Type};
    let socket = Socket::new(Domain::for_address(addr), Type::DGRAM, Some(Protocol::UDP))?;
    // A smaller buffer only makes bursts lossier; it is no reason to refuse to run.
    let _ = socket.set_recv_buffer_size(RECEIVE_BUFFER);
    socket.bind(&addr.into())?;
    Ok(socket.into())
}

fn arm_model(kind: ArmKind, config: &ValidRobot, start: Joints) -> ArmModel {
    match kind {
        ArmKind::Ideal => ArmModel::Ideal(IdealArm::new(start)),
        ArmKind::RateLimited => ArmModel::RateLimited(RateLimitedArm::new(
            start,
            config.per_joint(|j| j.max_rate),
            config.per_joint(|j| j.max_acceleration),
        )),
    }
}

/// Prints the tool pose at the drives' home angles, as the PS reply and the client show it.
fn print_home(config: &ValidRobot) {
    let chain = Chain::new(config);
    let home = config.home();
    let (Ok(tool), Ok(w)) = (chain.forward(&home), chain.manipulability(&home)) else {
        eprintln!("armgate-sim: home pose outside the model");
        return;
    };
    let [x, y, z]: [f64; 3] = tool.translation.vector.into();
    let [qx, qy, qz, qw] = Quaternion::from_rotation(&tool.rotation).to_array();
    let [roll, pitch, yaw] = math::rpy(&tool.rotation);
    println!(
        "{}: {} joints, control period {} s",
        config.name,
        chain.dof(),
        config.control_period
    );
    let joints: Vec<String> = home.iter().map(|q| format!("{q:.4}")).collect();
    println!(
        "home joints (rad; m for prismatic joints): {}",
        joints.join(" ")
    );
    println!("tool position (m):           {x:.4} {y:.4} {z:.4}");
    println!("tool quaternion (x y z w):   {qx:.4} {qy:.4} {qz:.4} {qw:.4}");
    println!("tool RPY (rad):              {roll:.4} {pitch:.4} {yaw:.4}");
    println!("manipulability:              {w:.6}");
}
