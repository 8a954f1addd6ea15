//! The `armgate` command line.

use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::time::{Duration, Instant};

use clap::{Args, Parser, Subcommand, ValueEnum};

use crate::banks::MAX_JOINTS;
use crate::matching;
use crate::runfile::{RunFile, RunFileError};
use crate::teleop::{self, TeleopOptions};
use crate::{
    Client, ClientConfig, ClientError, DEFAULT_ADDR, DEFAULT_RETRIES, Mode, NO_READING, Pose,
    Progress, Text, WaitOptions,
};

const ABOUT: &str = "Command an armgate robot-arm controller over UDP";

const LONG_ABOUT: &str = "\
Command an armgate robot-arm controller over its 31-byte UDP protocol (docs/protocol.md).

Each command sends one or a few requests and prints the answer. The controller is found at
--addr (default 127.0.0.1:7031, where armgate-sim listens), or at $ARMGATE_ADDR. A request
without reply within --timeout is sent again, --retries times.

Units: metres and radians; roll/pitch/yaw mean R = Rz(yaw)·Ry(pitch)·Rx(roll).
Motions need the right mode first: `armgate mode cart` for move/run with [[cartesian]] points,
`armgate mode joint` for jmove/run with [[joint]] points.";

const AFTER_HELP: &str = "\
Examples:
  armgate pose                               where is the tool?
  armgate mode cart
  armgate move 0.5 0.2 0.1 0 0 0 --time 5    GT + BG, then wait until within 1 mm
  armgate mode joint
  armgate jmove 0 0.5 1.0 0 0.3 0            jG + jB, then wait
  armgate run client/examples/rectangle.toml via points from a file
  armgate send PS                            any request, printed raw
  armgate send XY                            shows the controller's ER00 text
  armgate --joints 8 joints                  an 8-joint arm (two jP requests)
  armgate teleop                             keyboard client (Fig. 3.3 of the thesis)
  armgate calibrate plan --robot robots/ur5.toml --poses 50
                                             poses to measure for kinematic calibration

Exit status: 0 success, 1 the controller refused (ER text) or aborted a motion (ER21, WN22,
WN27, ER3x), 2 no reply, I/O error, bad arguments or a bad run file.
Unsolicited ER/WN notices that arrive meanwhile are printed to stderr.";

const RUN_LONG: &str = "\
Run a via-point sequence from a TOML file and wait until its last point is reached.

The file holds up to 20 [[cartesian]] entries or up to 20 [[joint]] entries, not both:

  [[cartesian]]
  xyz = [0.5, 0.2, 0.1]     # position, m
  rpy = [0.0, 0.0, 0.0]     # roll, pitch, yaw, rad
  time = 5.0                # minimum seconds for the leg to this point (default 0)

  [[joint]]
  q = [0.0, 0.5, 1.0, 0.0, 0.3, 0.0]   # one value per joint (--joints)
  time = 3.0

The entries go into via slots 0.. in file order and run: VC, VP 0.., VE (needs mode cart)
or jC, jV 0.., jE (needs mode joint). The first leg starts wherever the arm is. The wait
follows the points in order and ends within --tolerance of the last one.

client/examples/rectangle.toml is the seed thesis's E8 rectangle: (0.5, 0.2, 0.1) ->
(0.5, 0.2, 0.4) -> (0.5, -0.2, 0.4) -> (0.5, -0.2, 0.1) -> back to the start.";

const TELEOP_LONG: &str = "\
The keyboard client (thesis Fig. 3.3): Current Pose, Desired Pose, Joints and Temp(C),
polled from PS, jP and TM; the RPY of both poses, the scale, and the latest ER/WN text.

Keys edit the desired pose; Enter sends it (with --live, every key press sends).

  Cartesian keys              Joint keys (after j)
  Left / Right   x - / +      Left / Right   selected joint - / +
  Down / Up      y - / +      Up / Down      select previous / next joint
  PgDn / PgUp    z - / +      1 .. 8         select joint 1 .. 8
  + / -          double / halve the scale
  space          desired <- current
  Enter          GT (desired position, current roll/pitch/yaw, T = 0) + BG;
                 joint keys: jG + jB.
                 If BG (jB) is refused, e.g. a motion still runs: ST, then BG (jB) once more.
  j              switch between Cartesian and joint keys
  m              next mode via CM: off -> joint -> cart -> off (the first m selects joint)
  q, Esc         quit (the terminal is restored)

A Cartesian step is 1 mm x scale, a joint step 0.01 rad x scale.";

/// The `armgate` command line.
#[derive(Debug, Parser)]
#[command(name = "armgate", version, about = ABOUT, long_about = LONG_ABOUT, after_help = AFTER_HELP)]
pub struct Cli {
    /// The controller's address, host:port.
    #[arg(long, global = true, env = "ARMGATE_ADDR", default_value = DEFAULT_ADDR)]
    pub addr: String,
    /// How long to wait for each reply: 200ms, 1s, 1.5s, or a number of milliseconds.
    #[arg(long, global = true, default_value = "200ms", value_parser = parse_duration)]
    pub timeout: Duration,
    /// How many times a request is sent again when no reply came.
    #[arg(long, global = true, default_value_t = DEFAULT_RETRIES)]
    pub retries: u32,
    /// How many joints the arm has, 1 to 8 (the replies do not say). Joint lists must have this
    /// many values; more than 6 joints use the two-bank requests.
    #[arg(long, global = true, default_value_t = 6, value_parser = parse_joints)]
    pub joints: usize,
    /// What to do.
    #[command(subcommand)]
    pub command: Cmd,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Cmd {
    /// Send any request and print the reply: its characters, 7 floats and the index, or the
    /// ER/WN text (the seed's text client).
    #[command(after_help = "Example: armgate send GT 0.5 0.2 0.1 0 0 0 5")]
    Send {
        /// The two command characters, case-sensitive (PS, GT, jV, ...).
        chars: String,
        /// f0..f6; missing values are sent as 0.
        #[arg(num_args = 0..=7, allow_negative_numbers = true)]
        values: Vec<f32>,
        /// The index byte (via slot; bit 7 = joint bank 2).
        #[arg(long, short, default_value_t = 0)]
        index: u8,
    },
    /// Print the measured tool pose: position, quaternion (x, y, z, w) and roll/pitch/yaw (PS).
    Pose,
    /// Print the measured joints (jP; two requests for more than 7 joints).
    Joints,
    /// Print the drive temperatures (TM).
    Temps,
    /// Change the control mode (CM).
    Mode {
        /// off (0), joint (1) or cart (2).
        mode: ModeArg,
    },
    /// Start the drives (ON); also clears a drive fault.
    On,
    /// Stop the drives (OF).
    Off,
    /// Stop every motion and sequence; the arm holds its position (ST).
    Stop,
    /// Move the tool to a pose (GT + BG, Cartesian mode) and wait until it is within the
    /// tolerance (1 mm, 0.01 rad), showing the remaining distance.
    #[command(after_help = "Example: armgate move 0.5 -0.2 0.4 0 0 -1.5708 --time 4")]
    Move {
        /// x (m).
        #[arg(allow_negative_numbers = true)]
        x: f64,
        /// y (m).
        #[arg(allow_negative_numbers = true)]
        y: f64,
        /// z (m).
        #[arg(allow_negative_numbers = true)]
        z: f64,
        /// Roll, about the base x axis (rad).
        #[arg(allow_negative_numbers = true)]
        roll: f64,
        /// Pitch, about the base y axis (rad).
        #[arg(allow_negative_numbers = true)]
        pitch: f64,
        /// Yaw, about the base z axis (rad).
        #[arg(allow_negative_numbers = true)]
        yaw: f64,
        /// Minimum duration (s); 0 = as fast as the controller's limits allow.
        #[arg(long, default_value_t = 0.0)]
        time: f64,
        /// Waiting.
        #[command(flatten)]
        wait: WaitArgs,
    },
    /// Move the joints (joint mode) and wait until within the tolerance (1 mrad).
    ///
    /// Without --time: jG + jB, a minimum-time motion. With --time T: jC, jV slot 0 with T, jE,
    /// since jB takes no duration (this clears the joint via points).
    #[command(after_help = "Example: armgate jmove 0 0.5 1.0 0 0.3 0 --time 3")]
    Jmove {
        /// One value per joint (rad, or m for prismatic joints); --joints says how many.
        #[arg(required = true, num_args = 1..=MAX_JOINTS, allow_negative_numbers = true)]
        q: Vec<f64>,
        /// Minimum duration (s).
        #[arg(long)]
        time: Option<f64>,
        /// Waiting.
        #[command(flatten)]
        wait: WaitArgs,
    },
    /// Run a via-point sequence from a TOML file and wait until its last point is reached.
    #[command(long_about = RUN_LONG)]
    Run {
        /// The run file.
        file: PathBuf,
        /// Waiting.
        #[command(flatten)]
        wait: WaitArgs,
    },
    /// The keyboard client: live pose, joints and temperatures; move with the arrow keys.
    #[command(long_about = TELEOP_LONG)]
    Teleop {
        /// Send on every key press instead of on Enter.
        #[arg(long)]
        live: bool,
        /// How often to read PS, jP and TM (Hz).
        #[arg(long, default_value_t = 10.0)]
        rate: f64,
    },
    /// Kinematic calibration: runs `armgate-calibrate` with these arguments (its `--help`
    /// explains them; docs/calibration.md). Needs no controller.
    #[command(disable_help_flag = true)]
    Calibrate {
        /// Passed on unchanged, e.g. `--robot R.toml --measurements M.csv --out C.toml` or
        /// `plan --robot R.toml --poses 50`.
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<std::ffi::OsString>,
    },
}

/// The modes, as typed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ModeArg {
    /// 0: no generator drives the arm.
    Off,
    /// 1: joint mode.
    Joint,
    /// 2: Cartesian mode.
    Cart,
}

impl From<ModeArg> for Mode {
    fn from(mode: ModeArg) -> Self {
        match mode {
            ModeArg::Off => Self::Off,
            ModeArg::Joint => Self::Joint,
            ModeArg::Cart => Self::Cartesian,
        }
    }
}

/// Options of the commands that wait for a motion.
#[derive(Clone, Debug, Args)]
pub struct WaitArgs {
    /// Return as soon as the motion has started.
    #[arg(long)]
    pub no_wait: bool,
    /// Give up waiting after this long (default: 30 s plus the requested times).
    #[arg(long, value_parser = parse_duration)]
    pub wait_timeout: Option<Duration>,
    /// Arrival tolerance, mm (joints: mrad).
    #[arg(long, default_value_t = 1.0)]
    pub tolerance: f64,
}

impl WaitArgs {
    fn options(&self, requested: f64) -> WaitOptions {
        let extra = Duration::try_from_secs_f64(requested).unwrap_or_default();
        WaitOptions {
            tolerance: self.tolerance * 1e-3,
            timeout: self.wait_timeout.unwrap_or(Duration::from_secs(30) + extra),
            ..WaitOptions::default()
        }
    }
}

/// Why a command failed.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// From the client.
    #[error(transparent)]
    Client(#[from] ClientError),
    /// A bad run file.
    #[error(transparent)]
    RunFile(#[from] RunFileError),
    /// A bad argument.
    #[error("{0}")]
    Usage(String),
    /// Writing the output failed.
    #[error("output: {0}")]
    Output(#[from] std::io::Error),
}

impl CliError {
    /// 1 if the controller refused or aborted, else 2.
    pub fn exit_code(&self) -> u8 {
        match self {
            Self::Client(e) => e.exit_code(),
            _ => 2,
        }
    }
}

/// Parses `200ms`, `1s`, `1.5s` or a plain number of milliseconds.
pub fn parse_duration(s: &str) -> Result<Duration, String> {
    let s = s.trim();
    let (number, scale) = if let Some(ms) = s.strip_suffix("ms") {
        (ms, 1e-3)
    } else if let Some(secs) = s.strip_suffix('s') {
        (secs, 1.0)
    } else {
        (s, 1e-3)
    };
    number
        .trim()
        .parse::<f64>()
        .ok()
        .and_then(|v| Duration::try_from_secs_f64(v * scale).ok())
        .ok_or_else(|| format!("`{s}` is not a duration (e.g. 200ms, 1.5s)"))
}

fn parse_joints(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(n) if (1..=MAX_JOINTS).contains(&n) => Ok(n),
        _ => Err(format!("`{s}`: the number of joints is 1 to {MAX_JOINTS}")),
    }
}

/// Runs the command line (parsed from the process's arguments) and returns the exit status.
pub fn main() -> u8 {
    let cli = Cli::parse();
    if let Cmd::Calibrate { args } = &cli.command {
        return crate::calibrate::run(args);
    }
    let mut out = std::io::stdout().lock();
    match run(&cli, &mut out) {
        Ok(()) => 0,
        Err(e) => {
            let _ = out.flush();
            eprintln!("armgate: {e}");
            if let CliError::Client(ClientError::Rejected(text)) = &e
                && let Some(hint) = hint(text)
            {
                eprintln!("hint: {hint}");
            }
            e.exit_code()
        }
    }
}

/// A hint for a refusal whose cause is usually the mode.
fn hint(text: &Text) -> Option<&'static str> {
    if matching::code(text) != Some(20) {
        return None;
    }
    let s = text.as_str();
    let named = |chars: &[&str]| chars.iter().any(|c| s.contains(&format!("Cmd {c} ")));
    if named(&["BG", "VE"]) {
        Some(
            "needs Cartesian mode (`armgate mode cart`), a goal, and no motion running (`armgate stop`)",
        )
    } else if named(&["jB", "jE"]) {
        Some("needs joint mode (`armgate mode joint`) and no motion running (`armgate stop`)")
    } else if named(&["RC"]) {
        Some("recalibration needs mode off (`armgate mode off`)")
    } else {
        None
    }
}

/// Runs a parsed command, writing results to `out` and notices and progress to stderr.
pub fn run(cli: &Cli, out: &mut impl Write) -> Result<(), CliError> {
    let config = ClientConfig {
        timeout: cli.timeout,
        retries: cli.retries,
        ..ClientConfig::default()
    };
    let mut client = Client::connect_with(cli.addr.as_str(), config)?;
    if let Cmd::Teleop { live, rate } = &cli.command {
        let poll = Some(1.0 / rate)
            .filter(|p| *p > 0.0)
            .and_then(|p| Duration::try_from_secs_f64(p).ok())
            .ok_or_else(|| CliError::Usage(format!("--rate {rate}: must be > 0")))?;
        let options = TeleopOptions {
            joints: cli.joints,
            live: *live,
            poll,
            addr: cli.addr.clone(),
        };
        return teleop::run(client, options).map_err(CliError::Output);
    }
    let result = dispatch(cli, &mut client, out);
    print_notices(&mut client);
    result
}

fn print_notices(client: &mut Client) {
    let _ = client.poll_notices();
    for notice in client.take_notices() {
        eprintln!("notice: {notice}");
    }
}

fn dispatch(cli: &Cli, client: &mut Client, out: &mut impl Write) -> Result<(), CliError> {
    let n = cli.joints;
    match &cli.command {
        Cmd::Send {
            chars,
            values,
            index,
        } => send(client, chars, values, *index, out),
        Cmd::Pose => print_pose(&client.pose()?, out),
        Cmd::Joints => {
            let q = client.joints(n)?;
            writeln!(out, "joints (rad; m for prismatic joints)")?;
            for (k, v) in q.iter().enumerate() {
                writeln!(out, "  q{:<2} {v:>10.6}", k + 1)?;
            }
            Ok(())
        }
        Cmd::Temps => {
            let t = client.temperatures(n)?;
            writeln!(out, "drive temperatures (°C)")?;
            for (k, v) in t.iter().enumerate() {
                if *v == NO_READING {
                    writeln!(out, "  T{:<2}   no reading yet", k + 1)?;
                } else {
                    writeln!(out, "  T{:<2} {v:>6.1}", k + 1)?;
                }
            }
            Ok(())
        }
        Cmd::Mode { mode } => {
            let reported = client.set_mode((*mode).into())?;
            writeln!(out, "mode {} ({})", reported.name(), reported.value())?;
            Ok(())
        }
        Cmd::On => ok(client.on(), "drives on", out),
        Cmd::Off => ok(client.off(), "drives off", out),
        Cmd::Stop => ok(client.stop(), "stopped", out),
        Cmd::Move {
            x,
            y,
            z,
            roll,
            pitch,
            yaw,
            time,
            wait,
        } => {
            let (xyz, rpy) = ([*x, *y, *z], [*roll, *pitch, *yaw]);
            client.goal_rpy(xyz, rpy, *time)?;
            client.begin()?;
            writeln!(out, "moving")?;
            if wait.no_wait {
                return Ok(());
            }
            let goal = Pose::from_xyz_rpy(xyz, rpy);
            let pose = client.wait_until_pose(&goal, &wait.options(*time), pose_progress)?;
            finish_progress();
            writeln!(
                out,
                "arrived: {} ({:.2} mm from the goal)",
                fmt_values(&pose.xyz, 4),
                pose.distance(&goal) * 1e3
            )?;
            Ok(())
        }
        Cmd::Jmove { q, time, wait } => {
            check_joint_count(q.len(), n)?;
            match time {
                None => {
                    client.joint_goal(q)?;
                    client.joint_begin()?;
                }
                Some(t) => {
                    client.joint_via_clear()?;
                    client.via_joint(0, q, *t)?;
                    client.run_joint_sequence()?;
                }
            }
            writeln!(out, "moving")?;
            if wait.no_wait {
                return Ok(());
            }
            let reached =
                client.wait_until_joints(q, &wait.options(time.unwrap_or(0.0)), joint_progress)?;
            finish_progress();
            writeln!(out, "arrived: {}", fmt_values(&reached, 4))?;
            Ok(())
        }
        Cmd::Run { file, wait } => {
            let run = RunFile::load(file, n)?;
            client.start_run(&run)?;
            writeln!(
                out,
                "running {} via points from {}",
                run.len(),
                file.display()
            )?;
            if wait.no_wait {
                return Ok(());
            }
            match &run {
                RunFile::Cartesian(points) => {
                    let total = points.iter().map(|p| p.time).sum();
                    let goals = RunFile::poses(points);
                    let pose =
                        client.wait_through_poses(&goals, &wait.options(total), pose_progress)?;
                    finish_progress();
                    writeln!(out, "done: {}", fmt_values(&pose.xyz, 4))?;
                }
                RunFile::Joint(points) => {
                    let total = points.iter().map(|p| p.time).sum();
                    let goals: Vec<Vec<f64>> = points.iter().map(|p| p.q.clone()).collect();
                    let q =
                        client.wait_through_joints(&goals, &wait.options(total), joint_progress)?;
                    finish_progress();
                    writeln!(out, "done: {}", fmt_values(&q, 4))?;
                }
            }
            Ok(())
        }
        // Handled in `run`, which hands the client over.
        Cmd::Teleop { .. } | Cmd::Calibrate { .. } => Ok(()),
    }
}

fn check_joint_count(given: usize, joints: usize) -> Result<(), CliError> {
    if given == joints {
        Ok(())
    } else {
        Err(CliError::Usage(format!(
            "{given} joint values, but the arm has {joints} joints (set --joints)"
        )))
    }
}

fn ok(result: Result<(), ClientError>, what: &str, out: &mut impl Write) -> Result<(), CliError> {
    result?;
    writeln!(out, "{what}")?;
    Ok(())
}

fn send(
    client: &mut Client,
    chars: &str,
    values: &[f32],
    index: u8,
    out: &mut impl Write,
) -> Result<(), CliError> {
    let pair: [u8; 2] = chars
        .as_bytes()
        .try_into()
        .ok()
        .filter(|p: &[u8; 2]| p.iter().all(u8::is_ascii_graphic))
        .ok_or_else(|| CliError::Usage(format!("`{chars}`: give two command characters")))?;
    let mut all = [0.0; 7];
    all.iter_mut().zip(values).for_each(|(a, v)| *a = *v);
    let reply = client.send_raw(pair, all, index)?;
    let values: Vec<String> = reply.values.iter().map(|v| format!("{v:.6}")).collect();
    writeln!(
        out,
        "{}  {}  index {}",
        String::from_utf8_lossy(&reply.chars),
        values.join(" "),
        reply.index
    )?;
    Ok(())
}

fn fmt_values(values: &[f64], decimals: usize) -> String {
    let parts: Vec<String> = values.iter().map(|v| format!("{v:.decimals$}")).collect();
    parts.join(" ")
}

/// Writes a pose: position, quaternion and roll/pitch/yaw (spec §2.4, with its gimbal branch).
pub fn print_pose(pose: &Pose, out: &mut impl Write) -> Result<(), CliError> {
    let [x, y, z] = pose.xyz;
    let q = pose.quaternion;
    let [roll, pitch, yaw] = pose.rpy();
    writeln!(
        out,
        "position (m)     x {x:>10.6}  y {y:>10.6}  z {z:>10.6}"
    )?;
    writeln!(
        out,
        "quaternion       x {:>10.6}  y {:>10.6}  z {:>10.6}  w {:>10.6}",
        q.x, q.y, q.z, q.w
    )?;
    writeln!(
        out,
        "RPY (rad)     roll {roll:>10.6}  pitch {pitch:>10.6}  yaw {yaw:>10.6}"
    )?;
    writeln!(
        out,
        "RPY (deg)     roll {:>10.4}  pitch {:>10.4}  yaw {:>10.4}",
        roll.to_degrees(),
        pitch.to_degrees(),
        yaw.to_degrees()
    )?;
    Ok(())
}

/// The state of the progress line on stderr.
struct ProgressLine {
    tty: bool,
    last: Option<Instant>,
}

thread_local! {
    static PROGRESS: std::cell::RefCell<ProgressLine> = std::cell::RefCell::new(ProgressLine {
        tty: std::io::stderr().is_terminal(),
        last: None,
    });
}

/// Prints a progress line: rewritten in place on a terminal, once a second otherwise.
fn progress_line(line: &str, notices: &[Text]) {
    PROGRESS.with_borrow_mut(|p| {
        let mut err = std::io::stderr().lock();
        for notice in notices {
            if p.tty && p.last.is_some() {
                let _ = writeln!(err);
            }
            let _ = writeln!(err, "notice: {notice}");
        }
        if p.tty {
            let _ = write!(err, "\r\x1b[2K{line}");
            let _ = err.flush();
            p.last = Some(Instant::now());
        } else if p.last.is_none_or(|t| t.elapsed() >= Duration::from_secs(1)) {
            let _ = writeln!(err, "{line}");
            p.last = Some(Instant::now());
        }
    });
}

/// Ends the progress line.
fn finish_progress() {
    PROGRESS.with_borrow_mut(|p| {
        if p.tty && p.last.is_some() {
            eprintln!();
        }
        p.last = None;
    });
}

fn pose_progress(p: &Progress<'_, Pose>) {
    let [x, y, z] = p.current.xyz;
    let point = if p.targets > 1 {
        format!("point {}/{}: ", p.target + 1, p.targets)
    } else {
        String::new()
    };
    let angle = p.angle.map_or(String::new(), |a| format!(", {a:.3} rad"));
    progress_line(
        &format!(
            "{point}{:8.1} mm{angle} to go   at x {x:.4} y {y:.4} z {z:.4}   {:.1} s",
            p.distance * 1e3,
            p.elapsed.as_secs_f64()
        ),
        p.notices,
    );
}

fn joint_progress(p: &Progress<'_, [f64]>) {
    let point = if p.targets > 1 {
        format!("point {}/{}: ", p.target + 1, p.targets)
    } else {
        String::new()
    };
    progress_line(
        &format!(
            "{point}{:8.1} mrad to go   at {}   {:.1} s",
            p.distance * 1e3,
            fmt_values(p.current, 3),
            p.elapsed.as_secs_f64()
        ),
        p.notices,
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fake::{FakeController, text};
    use armgate_protocol::client::{Command, Message, Reply, Request};
    use clap::CommandFactory;

    #[test]
    fn the_command_line_is_consistent() {
        Cli::command().debug_assert();
    }

    #[test]
    fn negative_numbers_are_values() {
        let cli = Cli::try_parse_from([
            "armgate", "move", "0.5", "-0.2", "0.4", "0", "0", "-1.25", "--time", "4",
        ])
        .unwrap();
        let Cmd::Move { y, yaw, time, .. } = cli.command else {
            panic!()
        };
        assert_eq!((y, yaw, time), (-0.2, -1.25, 4.0));
        let cli = Cli::try_parse_from([
            "armgate", "--joints", "8", "jmove", "-1", "0", "0", "0", "0", "0", "0", "-0.5",
        ])
        .unwrap();
        assert_eq!(cli.joints, 8);
        let Cmd::Jmove { q, time: None, .. } = cli.command else {
            panic!()
        };
        assert_eq!(q.len(), 8);
        assert!(Cli::try_parse_from(["armgate", "--joints", "9", "pose"]).is_err());
        let cli =
            Cli::try_parse_from(["armgate", "send", "GT", "0.5", "-0.2", "--index", "3"]).unwrap();
        assert!(
            matches!(cli.command, Cmd::Send { ref values, index: 3, .. } if values == &[0.5, -0.2])
        );
    }

    #[test]
    fn durations() {
        assert_eq!(parse_duration("200ms"), Ok(Duration::from_millis(200)));
        assert_eq!(parse_duration("1.5s"), Ok(Duration::from_millis(1500)));
        assert_eq!(parse_duration("50"), Ok(Duration::from_millis(50)));
        assert!(parse_duration("soon").is_err());
        assert!(parse_duration("-1s").is_err());
    }

    fn run_with(fake: &FakeController, args: &[&str]) -> (Result<(), CliError>, String) {
        let addr = fake.addr().to_string();
        let mut argv = vec!["armgate", "--addr", addr.as_str(), "--timeout", "1s"];
        argv.extend_from_slice(args);
        let cli = Cli::try_parse_from(argv).unwrap();
        let mut out = Vec::new();
        let result = run(&cli, &mut out);
        (result, String::from_utf8(out).unwrap())
    }

    #[test]
    fn send_prints_the_reply_or_the_text() {
        let fake = FakeController::spawn(|d| {
            if &d[..2] == b"PS" {
                let mut r = Reply::null(Command::Pose);
                r.values = [0.5, 0.2, 0.1, 0.0, 0.0, 0.0, 1.0];
                vec![r.to_bytes().to_vec()]
            } else {
                vec![text("ER00 Cmd XY not understood")]
            }
        });
        let (result, out) = run_with(&fake, &["send", "PS"]);
        result.unwrap();
        assert_eq!(
            out,
            "SP  0.500000 0.200000 0.100000 0.000000 0.000000 0.000000 1.000000  index 0\n"
        );
        let (result, _) = run_with(&fake, &["send", "XY"]);
        let err = result.unwrap_err();
        assert_eq!(err.to_string(), "ER00 Cmd XY not understood");
        assert_eq!(err.exit_code(), 1);
    }

    #[test]
    fn pose_prints_rpy() {
        let fake = FakeController::spawn(|_| {
            let mut r = Reply::null(Command::Pose);
            let q = crate::pose::tests::GOLDEN_QUATERNION;
            r.values = [
                -0.0543, 0.5242, 0.2138, q.x as f32, q.y as f32, q.z as f32, q.w as f32,
            ];
            vec![r.to_bytes().to_vec()]
        });
        let (result, out) = run_with(&fake, &["pose"]);
        result.unwrap();
        assert!(out.contains("roll  -0.0007"), "{out}");
        assert!(out.contains("pitch   1.4801"), "{out}");
        assert!(
            out.contains("yaw   1.7917") || out.contains("yaw   1.7916"),
            "{out}"
        );
        assert!(out.contains("w   0.461231"), "{out}");
    }

    #[test]
    fn timeouts_exit_2_and_rejections_1() {
        let fake = FakeController::spawn(|d| {
            if &d[..2] == b"BG" {
                vec![text("ER20 Cmd BG rejected")]
            } else if &d[..2] == b"GT" {
                let mut r = d[..31].to_vec();
                r.swap(0, 1);
                vec![r]
            } else {
                vec![]
            }
        });
        let (result, _) = run_with(&fake, &["stop", "--timeout", "50ms", "--retries", "0"]);
        assert_eq!(result.unwrap_err().exit_code(), 2);
        let (result, _) = run_with(&fake, &["move", "0.5", "0.2", "0.1", "0", "0", "0"]);
        let err = result.unwrap_err();
        assert_eq!(err.exit_code(), 1);
        let CliError::Client(ClientError::Rejected(t)) = err else {
            panic!()
        };
        assert!(hint(&t).unwrap().contains("mode cart"));
    }

    #[test]
    fn jmove_with_a_time_uses_a_via_point() {
        let fake = FakeController::spawn(|d| {
            let m = Message::new_checked(d).unwrap();
            let r = Request::parse(&m).unwrap();
            let mut reply = Reply::null(r.command);
            reply.index = r.index;
            if r.command == Command::JointPosition {
                reply.values = [0.0, 0.5, 1.0, 0.0, 0.3, 0.0, 0.0];
            }
            vec![reply.to_bytes().to_vec()]
        });
        let (result, out) = run_with(
            &fake,
            &["jmove", "0", "0.5", "1.0", "0", "0.3", "0", "--time", "3"],
        );
        result.unwrap();
        assert!(out.contains("arrived"), "{out}");
        let sent: Vec<String> = fake
            .received()
            .iter()
            .map(|d| String::from_utf8_lossy(&d[..2]).into_owned())
            .collect();
        assert_eq!(sent[..3], ["jC", "jV", "jE"]);
        assert!(sent[3..].iter().all(|c| c == "jP"));
        let (result, _) = run_with(&fake, &["jmove", "0", "0.5"]);
        assert_eq!(result.unwrap_err().exit_code(), 2);
    }

    #[test]
    fn run_loads_the_file_into_via_slots() {
        let fake = FakeController::spawn(|d| {
            let m = Message::new_checked(d).unwrap();
            let r = Request::parse(&m).unwrap();
            let mut reply = Reply::null(r.command);
            reply.index = r.index;
            if r.command == Command::Pose {
                reply.values = [0.5, 0.2, 0.1, 0.0, 0.0, 0.0, 1.0];
            }
            vec![reply.to_bytes().to_vec()]
        });
        let file = std::env::temp_dir().join(format!("armgate-run-{}.toml", std::process::id()));
        std::fs::write(
            &file,
            "[[cartesian]]\nxyz = [0.5, 0.2, 0.1]\nrpy = [0, 0, 0]\n\
             [[cartesian]]\nxyz = [0.5, 0.2, 0.1]\nrpy = [0, 0, 0]\ntime = 1\n",
        )
        .unwrap();
        let (result, out) = run_with(&fake, &["run", file.to_str().unwrap()]);
        std::fs::remove_file(&file).unwrap();
        result.unwrap();
        assert!(out.contains("running 2 via points"), "{out}");
        let sent = fake.received();
        let chars: Vec<&[u8]> = sent.iter().map(|d| &d[..2]).collect();
        assert_eq!(chars[..4], [b"VC", b"VP", b"VP", b"VE"]);
        assert_eq!(sent[1][30], 0);
        assert_eq!(sent[2][30], 1);
    }
}
