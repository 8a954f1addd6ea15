//! `armgate-sim`: the armgate controller core on this computer, with a simulated arm.
//!
//! It runs the same core as the firmware: the control tick at the robot's period, and the
//! 31-byte UDP command protocol. Only bytes and time are handled here.

mod backend;
mod log;
mod pcap;
mod socketcan;

use std::io::IsTerminal;
use std::net::{IpAddr, Ipv4Addr, Ipv6Addr, SocketAddr, UdpSocket};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use armgate_core::command::{ArmModel, CommandHandler, Network};
use armgate_core::config::{ValidRobot, load_file};
use armgate_core::kinematics::{Chain, Joints};
use armgate_core::math::{self, Quaternion};
use armgate_core::motion::{IdealArm, RateLimitedArm};
use backend::{Backend, CanChoice};
use clap::{Parser, ValueEnum};
use log::{Logger, Record, Tick};

/// Run the armgate arm controller on this computer, with a simulated arm.
///
/// Clients command it with 31-byte UDP datagrams (docs/protocol.md), for example with the
/// `armgate` client: `armgate mode cart`, `armgate move 0.1 0.6 0.9 0 1.57 0`, `armgate pose`.
/// Only addresses on the allow-list may command the arm: anyone else on the network could move
/// it. Stop with Ctrl-C.
#[derive(Parser, Debug)]
#[command(version, about, long_about)]
struct Args {
    /// Robot description file (TOML); see docs/robot-file.md.
    #[arg(long, default_value = "robots/ranger-mk1.toml")]
    robot: PathBuf,
    /// UDP address to listen on for client commands.
    #[arg(long, default_value = "127.0.0.1:7031")]
    listen: SocketAddr,
    /// Networks allowed to send commands, e.g. 192.168.1.0/24 (repeatable). Default: loopback
    /// only (127.0.0.0/8 and ::1). Datagrams from elsewhere are dropped and counted.
    #[arg(long = "allow", value_name = "NETWORK")]
    allow: Vec<Network>,
    /// Where set-points go: `sim` = one simulated Elmo Whistle per drive of the robot file on
    /// a virtual CAN bus; `socketcan:IFACE` = real drives through Linux SocketCAN (e.g.
    /// socketcan:can0); `off` = no drives, a simulated arm (see --arm).
    #[arg(long, default_value = "sim", value_name = "sim|socketcan:IFACE|off")]
    can: CanChoice,
    /// With --can off: how the simulated joints follow the commands.
    #[arg(long, value_enum, default_value_t = ArmKind::Ideal)]
    arm: ArmKind,
    /// Starting joint positions, comma-separated (default: the drives' home positions).
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
    /// Exit after this many seconds (default: run until Ctrl-C).
    #[arg(long, value_name = "SECONDS")]
    duration: Option<f64>,
    /// No status line on the terminal.
    #[arg(long)]
    quiet: bool,
    /// Print the arm's pose at its home position and exit.
    #[arg(long)]
    print_home: bool,
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
    let config = match load_file(&args.robot) {
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

/// Counters shown in the status line and at exit.
#[derive(Debug, Default)]
struct Stats {
    received: u64,
    refused_sources: u64,
    notices: u64,
    overruns: u64,
}

fn run(args: &Args, config: &ValidRobot) -> Result<(), String> {
    let n = config.dof();
    let home = config.home();
    let start = Chain::new(config)
        .check(args.start.as_deref().unwrap_or(&home))
        .map_err(|e| format!("--start: {e} (the robot has {n} joints)"))?;
    let mut drives = Backend::open(&args.can, config, &start, || {
        arm_model(args.arm, config, start)
    })?;
    let mut handler = CommandHandler::new(config);
    let allow = if args.allow.is_empty() {
        vec![
            Network::new(IpAddr::V4(Ipv4Addr::LOCALHOST), 8),
            Network::new(IpAddr::V6(Ipv6Addr::LOCALHOST), 128),
        ]
    } else {
        args.allow.clone()
    };
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
    let socket = bind(args.listen).map_err(|e| format!("{}: {e}", args.listen))?;
    let local = socket.local_addr().map_err(|e| e.to_string())?;
    socket
        .set_nonblocking(true)
        .map_err(|e| format!("{}: {e}", args.listen))?;
    let running = Arc::new(AtomicBool::new(true));
    let stop = running.clone();
    ctrlc::set_handler(move || stop.store(false, Ordering::SeqCst))
        .map_err(|e| format!("Ctrl-C handler: {e}"))?;
    let allowed: Vec<String> = allow.iter().map(ToString::to_string).collect();
    eprintln!(
        "armgate-sim: {} ({n} joints, {:.2} ms period, drives: {}) on udp://{}, allowing {}",
        config.name,
        config.control_period * 1e3,
        drives.describe(),
        socket.local_addr().map_err(|e| e.to_string())?,
        allowed.join(", ")
    );

    let status = !args.quiet && std::io::stderr().is_terminal();
    let period = Duration::from_secs_f64(config.control_period);
    let epoch = Instant::now();
    let mut next_tick = epoch;
    let mut next_status = epoch;
    let mut last_sender: Option<SocketAddr> = None;
    let mut stats = Stats::default();
    let mut buf = [0u8; 64];
    while running.load(Ordering::SeqCst) {
        let now = Instant::now();
        if args
            .duration
            .is_some_and(|d| (now - epoch).as_secs_f64() >= d)
        {
            break;
        }
        if now >= next_tick {
            // Time inside the core is the scheduled tick time: deterministic, not wall-clock.
            let t = (next_tick - epoch).as_secs_f64();
            drives.receive(t)?;
            let out = handler
                .tick(t, &drives.measured(), drives.drives())
                .map_err(|e| format!("control tick: {e}"))?;
            drives.transmit(t, out.command.as_ref());
            while let Some(text) = handler.next_notice() {
                stats.notices += 1;
                logger.log(Record::Warning {
                    t,
                    text: text.as_str().to_string(),
                });
                if let Some(to) = last_sender {
                    // A lost warning is no reason to stop the arm; UDP gives no guarantee anyway.
                    let _ = socket.send_to(&text.to_bytes(), to);
                    pcap::udp(local, to, &text.to_bytes());
                }
            }
            if logger.enabled() {
                logger.log(Record::Tick(Box::new(Tick {
                    t,
                    mode: handler.controller().mode().name(),
                    pose: out.measured_pose,
                    joints: drives.measured(),
                    command: out.command,
                    setpoint: out.setpoint,
                })));
            }
            // Simulated time stays strictly periodic: after a late tick the next ones run back
            // to back (each one PT point for the drives) rather than skipping points, unless
            // the loop is hopelessly behind.
            next_tick += period;
            if now > next_tick + period * MAX_CATCH_UP {
                stats.overruns += 1;
                next_tick = now + period;
            }
            if status && now >= next_status {
                next_status = now + Duration::from_millis(250);
                eprint!("\r{}\x1b[K", status_line(&handler, &stats, &logger));
            }
            continue;
        }
        let (len, from) = match socket.recv_from(&mut buf) {
            Ok(received) => received,
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                // Socket timeouts are rounded to the kernel's tick (several ms); a sleep is
                // precise. Replies wait at most POLL_INTERVAL.
                std::thread::sleep((next_tick - now).min(POLL_INTERVAL));
                continue;
            }
            Err(e) => return Err(format!("udp receive: {e}")),
        };
        // Captured before the allow-list: a refused client is what one looks for in a capture.
        pcap::udp(from, local, buf.get(..len).unwrap_or(&[]));
        if !allow.iter().any(|net| net.contains(from.ip())) {
            stats.refused_sources += 1;
            continue;
        }
        stats.received += 1;
        last_sender = Some(from);
        let datagram = buf.get(..len).unwrap_or(&[]);
        let t = (Instant::now() - epoch).as_secs_f64();
        logger.log(Record::Command {
            t,
            datagram: datagram.to_vec(),
        });
        let reply = handler.handle(datagram, drives.drives_mut());
        logger.log(Record::Reply { t, datagram: reply });
        socket
            .send_to(&reply, from)
            .map_err(|e| format!("udp send to {from}: {e}"))?;
        pcap::udp(local, from, &reply);
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
    eprintln!(
        "armgate-sim: stopped; {} datagrams handled, {} from sources not allowed (dropped), {} warnings sent, {} tick overruns, {} log records dropped",
        stats.received, stats.refused_sources, stats.notices, stats.overruns, dropped
    );
    Ok(())
}

/// Longest wait for a datagram between two checks of the tick clock.
const POLL_INTERVAL: Duration = Duration::from_micros(500);
/// Late ticks are caught up back to back while the loop is at most this many periods behind.
const MAX_CATCH_UP: u32 = 50;

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

fn status_line(handler: &CommandHandler, stats: &Stats, logger: &Logger) -> String {
    let ctrl = handler.controller();
    let pose = ctrl
        .measured()
        .map(|(_, p)| {
            let [x, y, z]: [f64; 3] = p.translation.vector.into();
            format!("x {x:+.4} y {y:+.4} z {z:+.4}")
        })
        .unwrap_or_default();
    let state = if ctrl.is_moving() {
        "moving"
    } else {
        "holding"
    };
    format!(
        "mode {:<9} {state:<7} {pose} | rx {} refused {} warnings {} log dropped {}",
        ctrl.mode().name(),
        stats.received,
        stats.refused_sources,
        stats.notices,
        logger.dropped()
    )
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
    println!("home joints: {home:.4?}");
    println!("tool position (m):           {x:.4} {y:.4} {z:.4}");
    println!("tool quaternion (x y z w):   {qx:.4} {qy:.4} {qz:.4} {qw:.4}");
    println!("tool RPY (rad):              {roll:.4} {pitch:.4} {yaw:.4}");
    println!("manipulability:              {w:.6}");
}
