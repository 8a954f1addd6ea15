//! `armgate record FILE`: the same MCAP as `armgate-sim --mcap`, from any controller (the
//! firmware on a board), made of what the protocol can read: `jP` and `PS` at `--rate`, `SQ`
//! once a second, and every notice that arrives. Times are this program's clock from the start.
//! A controller has no command and set-point to read, and this client sees only its own
//! datagrams: `/joint_command`, `/setpoint`, `/goal`, `/planned_path` and `/can` stay empty.
//!
//! It fails (an error, exit status non-zero) when nothing was recorded — no reading answered:
//! nothing listening, a controller with a key and none given — and when the robot file does
//! not describe the controller's robot (its name or joint count differ from the status's):
//! a recording drawn with the wrong arm is worse than none (issue 37).

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
    /// Stop after this long (`60`, `60s`, `2min`; bare: seconds; default: until Ctrl-C or
    /// SIGTERM).
    #[arg(long, value_name = "DURATION", value_parser = armgate_client::cli::parse_seconds)]
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
    let mut mismatch = None;
    let mut checked = false;
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
                    log(&tap, t, Level::Info, peer, one_line(&status.to_string()));
                    if !checked {
                        checked = true;
                        mismatch = robot_mismatch(&status, robot).err();
                        if mismatch.is_some() {
                            break;
                        }
                    }
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
    if let Some(why) = mismatch {
        return Err(format!(
            "{why}: give the robot file the controller runs (`armgate status` names it)"
        ));
    }
    if polls == failed {
        return Err(format!(
            "nothing recorded: {polls} readings, none answered by {} (is the controller \
             running there? one with a signing key needs --key)",
            args.addr
        ));
    }
    Ok(())
}

/// Whether the robot file describes the controller's robot: the same name and joint count.
fn robot_mismatch(status: &armgate_client::Status, robot: &ValidRobot) -> Result<(), String> {
    if status.name == robot.name.as_str() && status.joints == robot.dof() {
        return Ok(());
    }
    Err(format!(
        "the controller runs `{}` ({} joints), the robot file describes `{}` ({} joints)",
        status.name,
        status.joints,
        robot.name.as_str(),
        robot.dof()
    ))
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::net::UdpSocket;

    fn robot(name: &str) -> ValidRobot {
        let path = format!("{}/../robots/{name}.toml", env!("CARGO_MANIFEST_DIR"));
        armgate_core::config::load_file(&path).unwrap()
    }

    fn args(addr: String, robot: &str, file: PathBuf) -> RecordArgs {
        RecordArgs {
            file,
            robot: PathBuf::from(robot),
            addr,
            rate: 20.0,
            duration: Some(0.5),
            key: None,
            link_id: None,
            controller_id: None,
        }
    }

    /// A controller of a six-joint `ranger-mk1` that answers `SQ` (status and name) and echoes
    /// everything else, until the test ends.
    fn six_joint_controller() -> String {
        let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
        let addr = socket.local_addr().unwrap().to_string();
        std::thread::spawn(move || {
            let mut buf = [0u8; 64];
            while let Ok((n, from)) = socket.recv_from(&mut buf) {
                if n < MESSAGE_LEN {
                    continue;
                }
                let mut reply = buf[..MESSAGE_LEN].to_vec();
                reply.swap(0, 1);
                if &buf[..2] == b"SQ" {
                    reply[2..30].fill(0);
                    if buf[30] == 1 {
                        reply[2..12].copy_from_slice(b"ranger-mk1");
                    } else {
                        let values = [2.0f32, 2.0, 0.0, 6.0, 0.0, 0.0, 1.0];
                        for (k, v) in values.iter().enumerate() {
                            reply[2 + 4 * k..6 + 4 * k].copy_from_slice(&v.to_le_bytes());
                        }
                    }
                }
                let _ = socket.send_to(&reply, from);
            }
        });
        addr
    }

    #[test]
    fn a_robot_file_of_another_arm_fails_the_recording() {
        let addr = six_joint_controller();
        let dir = std::env::temp_dir().join(format!("armgate-record-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let err = run(
            &args(addr.clone(), "iiwa14.toml", dir.join("a.mcap")),
            &robot("iiwa14"),
        )
        .unwrap_err();
        assert!(
            err.starts_with(
                "the controller runs `ranger-mk1` (6 joints), the robot file describes `iiwa14` \
                 (7 joints)"
            ),
            "{err}"
        );
        // The right file records.
        run(
            &args(addr, "ranger-mk1.toml", dir.join("b.mcap")),
            &robot("ranger-mk1"),
        )
        .unwrap();
    }

    #[test]
    fn a_recording_without_a_single_answer_fails() {
        // A socket that never answers.
        let silent = UdpSocket::bind("127.0.0.1:0").unwrap();
        let addr = silent.local_addr().unwrap().to_string();
        let file = std::env::temp_dir().join(format!("armgate-silent-{}.mcap", std::process::id()));
        let err = run(&args(addr, "ranger-mk1.toml", file), &robot("ranger-mk1")).unwrap_err();
        assert!(err.starts_with("nothing recorded: "), "{err}");
        assert!(err.contains("none answered"), "{err}");
    }
}
