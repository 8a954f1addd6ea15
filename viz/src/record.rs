//! `armgate record FILE`: the same MCAP as `armgate-sim --mcap`, from any controller (the
//! firmware on a board), made of what the protocol can read: `jP` and `PS` at `--rate`, `SQ`
//! once a second, and every notice that arrives. Times are this program's clock from the start.
//! A controller has no command and set-point to read, and this client sees only its own
//! datagrams: `/joint_command`, `/setpoint`, `/goal`, `/planned_path` and `/can` stay empty.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use armgate_client::{Client, ClientConfig, ClientError, Signer, interrupt};
use armgate_core::config::ValidRobot;
use armgate_core::kinematics::Joints;
use armgate_core::math::Frame;
use armgate_protocol::client::{MESSAGE_LEN, Message as Wire};
use armgate_viz::foxglove::Level;
use armgate_viz::mcap_file::McapFile;
use armgate_viz::recorder::{Recorder, Sink, Tap};
use armgate_viz::translate::Event;
use clap::Args;

/// `record`'s options.
#[derive(Debug, Args)]
pub struct RecordArgs {
    /// The MCAP file to write.
    file: PathBuf,
    /// The controller's robot file (for the URDF, the frames and the workspace).
    #[arg(long)]
    robot: PathBuf,
    /// The controller's address, host:port.
    #[arg(long, env = "ARMGATE_ADDR", default_value = armgate_client::DEFAULT_ADDR)]
    addr: String,
    /// How often to read jP and PS (Hz).
    #[arg(long, default_value_t = 20.0)]
    rate: f64,
    /// Stop after this many seconds (default: until Ctrl-C or SIGTERM).
    #[arg(long, value_name = "SECONDS")]
    duration: Option<f64>,
    /// Sign the requests with the key in this file, for a controller with a key
    /// (docs/safety.md, "Signing").
    #[arg(long, env = "ARMGATE_KEY_FILE", value_name = "FILE")]
    key: Option<PathBuf>,
    /// With --key: the link id to sign with, 1..=255 (default: a free one the controller sets
    /// aside).
    #[arg(long, env = "ARMGATE_LINK_ID")]
    link_id: Option<u8>,
    /// With --key: the controller's id, 8 hex digits (default: the one it names).
    #[arg(long, env = "ARMGATE_CONTROLLER_ID", value_name = "HEX")]
    controller_id: Option<armgate_protocol::client::signed::ControllerId>,
}

impl RecordArgs {
    /// The robot file.
    pub fn robot(&self) -> &std::path::Path {
        &self.robot
    }
}

/// `SQ` is read this often.
const STATUS_INTERVAL: Duration = Duration::from_secs(1);

/// Records until the duration ends or Ctrl-C/SIGTERM; the file is complete either way.
pub fn run(args: &RecordArgs, robot: &ValidRobot) -> Result<(), String> {
    if !(args.rate.is_finite() && args.rate > 0.0 && args.rate <= 1000.0) {
        return Err(format!("--rate {}: give 0 < Hz <= 1000", args.rate));
    }
    if let Some(d) = args.duration
        && !(d.is_finite() && d >= 0.0)
    {
        return Err(format!(
            "--duration {d}: give a number of seconds, 0 or more"
        ));
    }
    let stop = interrupt::ctrl_c()?;
    let config = ClientConfig {
        timeout: Duration::from_millis(200),
        retries: 1,
        ..ClientConfig::default()
    };
    let mut client = Client::connect_with(&args.addr, config).map_err(|e| e.to_string())?;
    if let Some(key) = &args.key {
        let mut signer = Signer::from_file(key, args.link_id).map_err(|e| e.to_string())?;
        if let Some(id) = args.controller_id {
            signer.set_controller(id);
        }
        client.set_signer(Some(signer));
    }
    let peer = client.peer();
    let local = client.local_addr().map_err(|e| e.to_string())?;
    let file = McapFile::create(&args.file, robot, "armgate record")
        .map_err(|e| format!("{}: {e}", args.file.display()))?;
    let sinks: Vec<Box<dyn Sink>> = vec![Box::new(file)];
    let recorder = Recorder::start(robot, 0.0, sinks).map_err(|e| e.to_string())?;
    let tap = recorder.tap();
    let period = Duration::from_secs_f64(1.0 / args.rate);
    let start = Instant::now();
    let mut next_status = start;
    let mut polls = 0u64;
    let mut failed = 0u64;
    while !stop.is_set() {
        let now = Instant::now();
        let t = (now - start).as_secs_f64();
        if args.duration.is_some_and(|d| t >= d) {
            break;
        }
        polls += 1;
        if let Err(e) = poll(&mut client, robot, &tap, t) {
            failed += 1;
            log(&tap, t, Level::Warning, peer, format!("no reading: {e}"));
        }
        if now >= next_status {
            next_status = now + STATUS_INTERVAL;
            match client.status() {
                Ok(status) => {
                    if status.name != robot.name.as_str() && next_status == start + STATUS_INTERVAL
                    {
                        eprintln!(
                            "armgate record: warning: the controller runs `{}`, the robot file \
                             describes `{}`",
                            status.name,
                            robot.name.as_str()
                        );
                    }
                    log(&tap, t, Level::Info, peer, one_line(&status.to_string()));
                }
                Err(e) => log(&tap, t, Level::Warning, peer, format!("status: {e}")),
            }
        }
        for notice in client.take_notices() {
            let mut bytes = [0u8; MESSAGE_LEN];
            if let Ok(mut message) = Wire::new_checked(&mut bytes[..]) {
                notice.emit(&mut message);
            }
            tap.record(Event::Answer {
                t,
                from: peer,
                to: local,
                bytes,
            });
        }
        let due = start + period.mul_f64((polls) as f64);
        if let Some(wait) = due.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
    }
    let dropped = tap.dropped();
    let (written, _) = recorder
        .finish()
        .map_err(|e| format!("{}: {e}", args.file.display()))?;
    eprintln!(
        "armgate record: {}: {polls} readings ({failed} without reply), {written} messages, \
         {dropped} events dropped (queue full)",
        args.file.display()
    );
    Ok(())
}

/// One reading: `jP` (both banks if needed) and `PS`.
fn poll(client: &mut Client, robot: &ValidRobot, tap: &Tap, t: f64) -> Result<(), ClientError> {
    let values = client.joints(robot.dof())?;
    let pose = client.pose()?;
    let mut measured = Joints::zeros(robot.dof());
    for (q, v) in measured.iter_mut().zip(values) {
        *q = v;
    }
    tap.record(Event::Joints {
        t,
        measured,
        command: None,
        setpoint: None,
        pose: Some(Frame::from_parts(pose.xyz.into(), pose.rotation())),
    });
    Ok(())
}

/// The status's lines as one: `robot ranger-mk1 (6 joints); mode off (0); …`.
fn one_line(text: &str) -> String {
    let lines: Vec<String> = text
        .lines()
        .map(|line| line.split_whitespace().collect::<Vec<_>>().join(" "))
        .collect();
    lines.join("; ")
}

fn log(tap: &Tap, t: f64, level: Level, peer: SocketAddr, text: String) {
    tap.record(Event::Log {
        t,
        level,
        name: peer.to_string(),
        text,
    });
}
