//! The `armgate` command line.

use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::time::{Duration, Instant};

use clap::{Args, Parser, Subcommand, ValueEnum};

use crate::banks::MAX_JOINTS;
use crate::drives;
use crate::hints;
use crate::interrupt;
use crate::runfile::{RunFile, RunFileError};
use crate::teleop::{self, TeleopOptions};
use crate::{
    Client, ClientConfig, ClientError, DEFAULT_ADDR, DEFAULT_RETRIES, DrivesOn, Mode, NO_READING,
    Pose, Progress, Text, TwistFrame, Velocity, WaitOptions,
};

const ABOUT: &str = "Command an armgate robot-arm controller over UDP";

const LONG_ABOUT: &str = "\
Command an armgate robot-arm controller over its 31-byte UDP protocol (docs/protocol.md).

Each command sends one or a few requests and prints the answer. The controller is found at
--addr (default 127.0.0.1:7031, where armgate-sim listens), or at $ARMGATE_ADDR. A request
without reply within --timeout is sent again, --retries times.

Units: metres and radians; roll/pitch/yaw mean R = Rz(yaw)·Ry(pitch)·Rx(roll).
Motions need the right mode first: `armgate mode cart` for move/run with [[cartesian]] points
and jog, `armgate mode joint` for jmove/run with [[joint]] points and jog --rates.";

const AFTER_HELP: &str = "\
Examples:
  armgate status                             mode, drives, joint count, robot name
  armgate pose                               where is the tool?
  armgate mode cart
  armgate move 0 0.2 0.8 0 0 -1.5708 --time 5
                                             GT + BG, then wait until within 1 mm
  armgate mode joint
  armgate jmove 1.5708 0.4 1.2 0 1.2 0       jG + jB, then wait
  armgate run client/examples/rectangle.toml via points from a file
  armgate jog 0 0 0.01 --for 2               TW stream: 1 cm/s up for 2 s, then a ramp to rest
  armgate send PS                            any request, printed raw
  armgate send XY                            shows the controller's ER00 text
  armgate --joints 8 joints                  override the joint count the controller reports
  armgate teleop                             keyboard client (Fig. 3.3 of the thesis)
  armgate calibrate plan --robot robots/ur5.toml --poses 50
                                             poses to measure for kinematic calibration
  armgate urdf robots/ur5.toml --out ur5.urdf
                                             the arm for URDF tools (Foxglove, RViz)
  armgate record run.mcap --robot robots/ranger-mk1.toml --duration 60
                                             the controller in MCAP for Foxglove

Exit status: 0 success, 1 the controller refused (ER text) or aborted a motion (ER21, WN22,
WN27, ER3x), 2 no reply, I/O error, bad arguments or a bad run file, 130 interrupted.
A move, ik-move, jmove or run that fails after starting its motion (Ctrl-C, --wait-timeout,
a stall, an abort, no reply) sends ST first and says so: the arm stops and holds.
Unsolicited ER/WN notices that arrive meanwhile are printed to stderr.";

const RUN_LONG: &str = "\
Run a via-point sequence from a TOML file and wait until its last point is reached.

The file holds up to 20 [[cartesian]] entries or up to 20 [[joint]] entries, not both:

  [[cartesian]]
  xyz = [0.5, 0.2, 0.1]     # position, m
  rpy = [0.0, 0.0, 0.0]     # roll, pitch, yaw, rad
  time = 5.0                # minimum seconds for the leg to this point (default 0)

  [[joint]]
  q = [1.5708, 0.4, 1.2, 0.0, 1.2, 0.0]   # one value per joint
  time = 3.0

  blend = 0.005             # optional, either kind: pass this point within 0.005 (m + rad,
                            # or rad for joints) without stopping; 0 stops there

The entries go into via slots 0.. in file order and run: VC, VP 0.., VE (needs mode cart)
or jC, jV 0.., jE (needs mode joint), with a VT (jT) for each point with a blend; --blend
gives every other point one (mm, or mrad for joints). The first leg starts wherever the arm
is. The wait follows the points in order and ends within --tolerance of the last one.

client/examples/rectangle.toml is a 0.2 m x 0.1 m rectangle for the default robot
(ranger-mk1): (0, 0.2, 0.8) -> (0.1, 0.2, 0.8) -> (0.1, 0.2, 0.7) -> (-0.1, 0.2, 0.7) ->
(-0.1, 0.2, 0.8) -> back. client/examples/rectangle-e8.toml is the seed thesis's E8 rectangle
for the hybrid and ranger-mk2 robots.";

const TELEOP_LONG: &str = "\
The keyboard client (thesis Fig. 3.3): Current Pose, Desired Pose, Joints and Temp(C),
polled from PS, jP and TM; the RPY of both poses, the scale, and the latest ER/WN text.

Jog keys (the default; v toggles): a held key moves the arm smoothly. The Cartesian keys
stream a twist (TW, base frame, 5 mm/s x scale along the axis), the joint keys joint rates
(jW, 0.02 rad/s x scale on the selected joint), re-sent every control period while the key
is held; on release the arm ramps to rest. Needs mode cartesian (joint) for the Cartesian
(joint) keys.

Step keys (--step, or v): keys edit the desired pose; Enter sends it (with --live, every key
press sends).

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
  m              next mode via CM, from the present one: off -> joint -> cart -> off
  v              jog keys <-> step keys
  q, Esc         quit (the terminal is restored)

A Cartesian step is 1 mm x scale, a joint step 0.01 rad x scale.";

/// The `armgate` command line.
#[derive(Debug, Parser)]
#[command(name = "armgate", version, about = ABOUT, long_about = LONG_ABOUT, after_help = AFTER_HELP)]
pub struct Cli {
    /// The controller's address, host:port.
    #[arg(long, global = true, env = "ARMGATE_ADDR", default_value = DEFAULT_ADDR)]
    pub addr: String,
    /// How long to wait for each reply: 200ms, 1s, 1.5s, or a number of milliseconds (> 0).
    #[arg(long, global = true, default_value = "200ms", value_parser = parse_timeout)]
    pub timeout: Duration,
    /// How many times a request is sent again when no reply came.
    #[arg(long, global = true, default_value_t = DEFAULT_RETRIES)]
    pub retries: u32,
    /// How many joints the arm has, 1 to 8. Default: what the controller's status (SQ) says,
    /// 6 if it is too old to say. Joint lists must have this many values; more than 6 joints
    /// use the two-bank requests.
    #[arg(long, global = true, value_parser = parse_joints)]
    pub joints: Option<usize>,
    /// Sign every request with the key in this file (64 hex digits on one line) and accept
    /// only answers signed with it, for a controller that has the key (docs/safety.md).
    #[arg(long, global = true, env = "ARMGATE_KEY_FILE", value_name = "FILE")]
    pub key: Option<std::path::PathBuf>,
    /// With --key: the link id to sign with, 1..=255; clients that run at the same time need
    /// their own (teleop also uses the next one, for its jog stream).
    #[arg(long, global = true, env = "ARMGATE_LINK_ID", default_value_t = crate::DEFAULT_LINK)]
    pub link_id: u8,
    /// What to do.
    #[command(subcommand)]
    pub command: Cmd,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Cmd {
    /// Send any request and print the reply: its characters, 7 floats and the index, or the
    /// ER/WN text (the seed's text client).
    #[command(after_help = "Example: armgate send GT 0 0.2 0.8 0 0 -1.5708 5")]
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
    /// Print the controller's state: robot, joint count, mode, drives (and their fault),
    /// motion, refused requests, uptime (SQ).
    Status,
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
    /// Start the drives (ON; also clears a drive fault) and wait until they run (SQ).
    On {
        /// Give up waiting for the drives after this long.
        #[arg(long, default_value = "5s", value_parser = parse_duration)]
        wait_timeout: Duration,
    },
    /// Stop the drives (OF).
    Off,
    /// Stop every motion and sequence; the arm holds its position (ST).
    Stop,
    /// Move the tool to a pose (GT + BG, Cartesian mode) and wait until it is within the
    /// tolerance (1 mm, 0.01 rad), showing the remaining distance.
    #[command(after_help = "Example: armgate move 0 0.2 0.8 0 0 -1.5708 --time 5")]
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
    /// Print every inverse-kinematics solution of a pose within the joint limits, each with
    /// its configuration branch (KS; robots with a closed form, docs/kinematics.md).
    #[command(after_help = "Example: armgate ik 0 0.2 0.8 0 0 -1.5708")]
    Ik {
        /// The pose.
        #[command(flatten)]
        pose: PoseArgs,
    },
    /// Move the joints (joint mode) to the inverse kinematics of a pose on a chosen
    /// configuration branch, or the solution nearest the present joints (KG), and wait.
    #[command(after_help = "Example: armgate ik-move 0 0.2 0.8 0 0 -1.5708")]
    IkMove {
        /// The pose.
        #[command(flatten)]
        pose: PoseArgs,
        /// Branch bits: 1 shoulder, 2 elbow, 4 wrist (as `armgate ik` prints them).
        #[arg(long, value_parser = clap::value_parser!(u8).range(0..8))]
        branch: Option<u8>,
        /// Minimum duration (s).
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
    #[command(after_help = "Example: armgate jmove 1.5708 0.4 1.2 0 1.2 0")]
    Jmove {
        /// One value per joint (rad, or m for prismatic joints), as many as the arm has.
        #[arg(required = true, num_args = 1..=MAX_JOINTS, allow_negative_numbers = true)]
        q: Vec<f64>,
        /// Minimum duration (s).
        #[arg(long)]
        time: Option<f64>,
        /// Waiting.
        #[command(flatten)]
        wait: WaitArgs,
    },
    /// Stream a velocity for a while, then let the arm ramp to rest: a tool twist (TW,
    /// Cartesian mode: vx vy vz in m/s, optionally wx wy wz in rad/s, base frame unless
    /// --tool) or, with --rates, one rate per joint (jW, joint mode: rad/s).
    #[command(after_help = "Example: armgate jog 0 0 -0.01 --for 1")]
    Jog {
        /// The twist (3 or 6 values) or the joint rates (one per joint).
        #[arg(required = true, num_args = 1..=MAX_JOINTS, allow_negative_numbers = true)]
        values: Vec<f64>,
        /// How long to stream (s).
        #[arg(long = "for", default_value_t = 1.0)]
        seconds: f64,
        /// The twist is in the tool frame.
        #[arg(long, conflicts_with = "rates")]
        tool: bool,
        /// The values are joint rates (jW), one per joint.
        #[arg(long)]
        rates: bool,
    },
    /// Run a via-point sequence from a TOML file and wait until its last point is reached.
    #[command(long_about = RUN_LONG)]
    Run {
        /// The run file.
        file: PathBuf,
        /// Blend tolerance, mm (joints: mrad), for every point without its own `blend`: the
        /// sequence passes through them within it without stopping (VT/jT).
        #[arg(long)]
        blend: Option<f64>,
        /// Waiting.
        #[command(flatten)]
        wait: WaitArgs,
    },
    /// The keyboard client: live pose, joints and temperatures; move with the arrow keys.
    #[command(long_about = TELEOP_LONG)]
    Teleop {
        /// Send on every key press instead of on Enter (step keys).
        #[arg(long)]
        live: bool,
        /// Keys step the desired values (the seed's teleop) instead of jogging while held.
        #[arg(long)]
        step: bool,
        /// How often to read PS, jP and TM (Hz).
        #[arg(long, default_value_t = 10.0)]
        rate: f64,
    },
    /// Kinematic calibration: runs `armgate-calibrate` with these arguments (its `--help`
    /// explains them; docs/calibration.md). Needs no controller.
    #[command(disable_help_flag = true)]
    Calibrate {
        /// Passed on unchanged, e.g. `--robot R.toml --measurements M.csv --out C.toml
        /// --instrument-out I.toml` or `plan --robot R.toml --poses 50`.
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<std::ffi::OsString>,
    },
    /// Write the URDF of a robot file, whose link frames are armgate's kinematics (runs
    /// `armgate-viz urdf`; docs/visualisation.md). Needs no controller.
    #[command(disable_help_flag = true)]
    Urdf {
        /// Passed on unchanged, e.g. `robots/ur5.toml --out ur5.urdf` (`--help` for more).
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<std::ffi::OsString>,
    },
    /// Record this controller into an MCAP file for Foxglove (runs `armgate-viz record --addr
    /// ADDR`; docs/visualisation.md): jP and PS at --rate, SQ once a second, every notice.
    #[command(disable_help_flag = true)]
    Record {
        /// Passed on unchanged, e.g. `run.mcap --robot robots/ranger-mk1.toml --rate 20`.
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<std::ffi::OsString>,
    },
    /// Draw SVG figures from armgate-sim's --log-dir CSVs: tool path, joints over time, mode
    /// changes and warnings (no controller needed).
    Plot(crate::plot::PlotArgs),
}

/// The modes, as typed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ModeArg {
    /// 0: no generator drives the arm.
    #[value(alias = "0")]
    Off,
    /// 1: joint mode.
    #[value(alias = "1")]
    Joint,
    /// 2: Cartesian mode (also `cartesian`, as the status shows it).
    #[value(aliases = ["cartesian", "2"])]
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

/// A pose: position (m) and roll/pitch/yaw (rad).
#[derive(Clone, Debug, Args)]
pub struct PoseArgs {
    /// x (m).
    #[arg(allow_negative_numbers = true)]
    pub x: f64,
    /// y (m).
    #[arg(allow_negative_numbers = true)]
    pub y: f64,
    /// z (m).
    #[arg(allow_negative_numbers = true)]
    pub z: f64,
    /// Roll, about the base x axis (rad).
    #[arg(allow_negative_numbers = true)]
    pub roll: f64,
    /// Pitch, about the base y axis (rad).
    #[arg(allow_negative_numbers = true)]
    pub pitch: f64,
    /// Yaw, about the base z axis (rad).
    #[arg(allow_negative_numbers = true)]
    pub yaw: f64,
}

impl PoseArgs {
    fn xyz_rpy(&self) -> ([f64; 3], [f64; 3]) {
        ([self.x, self.y, self.z], [self.roll, self.pitch, self.yaw])
    }
}

/// Options of the commands that wait for a motion.
#[derive(Clone, Debug, Args)]
pub struct WaitArgs {
    /// Return as soon as the motion has started.
    #[arg(long)]
    pub no_wait: bool,
    /// Give up waiting after this long (default: 30 s plus the requested times); then ST.
    #[arg(long, value_parser = parse_duration)]
    pub wait_timeout: Option<Duration>,
    /// Arrival tolerance, mm (joints: mrad).
    #[arg(long, default_value_t = 1.0)]
    pub tolerance: f64,
    /// On Ctrl-C just exit and leave the arm moving (by default ST is sent first).
    #[arg(long)]
    pub no_stop_on_interrupt: bool,
}

impl WaitArgs {
    /// The wait's options; with `interrupt`, Ctrl-C ends the wait.
    fn options(&self, requested: f64, interrupt: Option<&interrupt::Interrupt>) -> WaitOptions {
        let extra = Duration::try_from_secs_f64(requested).unwrap_or_default();
        WaitOptions {
            tolerance: self.tolerance * 1e-3,
            timeout: self
                .wait_timeout
                .unwrap_or(Duration::from_secs(30).saturating_add(extra)),
            interrupt: interrupt.cloned(),
            ..WaitOptions::default()
        }
    }

    /// The options of a wait through via points blended within `blend`: an intermediate
    /// point counts as passed within the blend plus the usual pass tolerance.
    fn passing(
        &self,
        requested: f64,
        interrupt: Option<&interrupt::Interrupt>,
        blend: f64,
    ) -> WaitOptions {
        let options = self.options(requested, interrupt);
        WaitOptions {
            pass_tolerance: options.pass_tolerance + blend,
            ..options
        }
    }

    /// Installs the Ctrl-C handler unless told not to (or there is no wait to interrupt).
    /// Installed before the first request, so that Ctrl-C while the motion is being started
    /// stops it as well.
    fn interrupt(&self) -> Option<interrupt::Interrupt> {
        if self.no_wait || self.no_stop_on_interrupt {
            return None;
        }
        interrupt::ctrl_c()
            .map_err(|e| eprintln!("armgate: {e}; Ctrl-C will not stop the arm"))
            .ok()
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
    /// `armgate plot` failed.
    #[error(transparent)]
    Plot(#[from] crate::plot::PlotError),
    /// The controller refused a request; the hint says what would help.
    #[error("{text}")]
    Refused {
        /// The refusal, with its reason.
        text: Text,
        /// What to do about it.
        hint: Option<String>,
    },
    /// Ctrl-C during a wait; says whether ST was sent.
    #[error("interrupted: {0}")]
    Interrupted(String),
    /// A command that started a motion failed before it saw it end; ST was sent first.
    #[error("{error}; {stop}")]
    Stopped {
        /// Why the command failed.
        error: ClientError,
        /// Whether ST was sent.
        stop: String,
    },
}

impl CliError {
    /// 1 if the controller refused or aborted, 130 if interrupted, else 2.
    pub fn exit_code(&self) -> u8 {
        match self {
            Self::Client(e) => e.exit_code(),
            Self::Refused { .. } => 1,
            Self::Interrupted(_) => ClientError::Interrupted.exit_code(),
            Self::Stopped { error, .. } => error.exit_code(),
            _ => 2,
        }
    }

    /// Whether the error is a closed output pipe (`armgate pose | head -1`): not worth a word.
    fn is_broken_pipe(&self) -> bool {
        matches!(self, Self::Output(e) if e.kind() == std::io::ErrorKind::BrokenPipe)
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

/// A duration that is not zero: a zero reply timeout would never wait for a reply.
pub fn parse_timeout(s: &str) -> Result<Duration, String> {
    match parse_duration(s)? {
        Duration::ZERO => Err(format!("`{s}`: the timeout must be longer than 0")),
        timeout => Ok(timeout),
    }
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
    match &cli.command {
        Cmd::Calibrate { args } => return crate::tools::run(crate::tools::CALIBRATE, args),
        Cmd::Urdf { args } => {
            let args = [&[std::ffi::OsString::from("urdf")], args.as_slice()].concat();
            return crate::tools::run(crate::tools::VIZ, &args);
        }
        Cmd::Record { args } => {
            let head = ["record", "--addr", cli.addr.as_str()].map(std::ffi::OsString::from);
            return crate::tools::run(crate::tools::VIZ, &[&head[..], args].concat());
        }
        _ => {}
    }
    let mut out = std::io::stdout().lock();
    let result = run(&cli, &mut out).and_then(|()| out.flush().map_err(CliError::Output));
    match result {
        Ok(()) => 0,
        // The reader has gone (`| head`): nobody is left to tell.
        Err(e) if e.is_broken_pipe() => 0,
        Err(e) => {
            let _ = out.flush();
            eprintln!("armgate: {e}");
            if let CliError::Refused {
                hint: Some(hint), ..
            } = &e
            {
                eprintln!("hint: {hint}");
            }
            if matches!(e, CliError::Client(ClientError::Timeout { .. })) && cli.key.is_none() {
                eprintln!(
                    "hint: a controller with a signing key never answers unsigned requests: \
                     --key FILE (or ARMGATE_KEY_FILE)"
                );
            }
            e.exit_code()
        }
    }
}

/// A refusal with its hint, asking the controller's state when it can tell (a refusal of `SQ`
/// itself, or a controller without it, leaves the hint to the text).
fn with_hint(client: &mut Client, error: CliError) -> CliError {
    let CliError::Client(ClientError::Rejected(text)) = error else {
        return error;
    };
    let status = client.status().ok();
    CliError::Refused {
        hint: hints::hint(&text, status.as_ref()),
        text,
    }
}

/// Runs a parsed command, writing results to `out` and notices and progress to stderr.
pub fn run(cli: &Cli, out: &mut impl Write) -> Result<(), CliError> {
    if let Cmd::Plot(args) = &cli.command {
        return crate::plot::run(args, out)
            .map(drop)
            .map_err(CliError::from);
    }
    let config = ClientConfig {
        timeout: cli.timeout,
        retries: cli.retries,
        ..ClientConfig::default()
    };
    let mut client = Client::connect_with(cli.addr.as_str(), config)?;
    if let Some(path) = &cli.key {
        client.set_signer(Some(crate::Signer::from_file(path, cli.link_id)?));
    }
    if let Cmd::Teleop { live, step, rate } = &cli.command {
        let poll = Some(1.0 / rate)
            .filter(|p| p.is_finite() && *p > 0.0)
            .and_then(|p| Duration::try_from_secs_f64(p).ok())
            .ok_or_else(|| CliError::Usage(format!("--rate {rate}: must be > 0")))?;
        let options = TeleopOptions {
            joints: joint_count(cli, &mut client)?,
            live: *live,
            jog: !*step,
            poll,
            addr: cli.addr.clone(),
        };
        return teleop::run(client, options).map_err(CliError::Output);
    }
    let result = dispatch(cli, &mut client, out).map_err(|e| with_hint(&mut client, e));
    print_notices(&mut client);
    result
}

/// `--joints`, else the joint count the controller reports, else (a controller without `SQ`) 6.
fn joint_count(cli: &Cli, client: &mut Client) -> Result<usize, CliError> {
    if let Some(n) = cli.joints {
        return Ok(n);
    }
    match client.status() {
        Ok(status) => Ok(status.joints),
        Err(e @ ClientError::TooOld { .. }) => {
            eprintln!("armgate: {e}; assuming 6 joints (set --joints)");
            Ok(6)
        }
        Err(e) => Err(e.into()),
    }
}

/// A command that leaves before it saw the motion it started end (a wait that timed out,
/// stalled, was aborted or interrupted; a controller that stopped answering) sends ST first:
/// otherwise the arm goes on alone, and the next client is refused (`ER40`) until it ends.
fn stop_started(client: &mut Client, error: ClientError) -> CliError {
    finish_progress();
    let stop = match client.stop() {
        Ok(()) => "sent ST: the arm stops and holds".to_owned(),
        Err(e) => format!("ST failed ({e}): the arm may still be moving"),
    };
    match error {
        ClientError::Interrupted => CliError::Interrupted(stop),
        error => CliError::Stopped { error, stop },
    }
}

/// Sends the request(s) that start a motion. When the starting request's replies are all lost,
/// the motion may have started: [`stop_started`].
fn start<T>(
    client: &mut Client,
    request: impl FnOnce(&mut Client) -> Result<T, ClientError>,
) -> Result<T, CliError> {
    request(client).map_err(|e| match e {
        ClientError::Timeout { .. } | ClientError::Unverified { .. } => stop_started(client, e),
        e => e.into(),
    })
}

/// Waits for the motion this command started (`wait`), then until it has ended ([`settle`]);
/// on any failure [`stop_started`].
fn follow<T>(
    client: &mut Client,
    wait: impl FnOnce(&mut Client) -> Result<T, ClientError>,
) -> Result<T, CliError> {
    let result = wait(client).and_then(|reached| {
        finish_progress();
        client.wait_motion_ended(SETTLE).map(|()| reached)
    });
    result.map_err(|e| stop_started(client, e))
}

/// `armgate jog`: a TW or jW stream for `seconds`, then wait until the arm has ramped to rest.
fn jog(
    cli: &Cli,
    client: &mut Client,
    values: &[f64],
    seconds: f64,
    (tool, rates): (bool, bool),
    out: &mut impl Write,
) -> Result<(), CliError> {
    let duration = Some(seconds)
        .filter(|s| s.is_finite() && *s > 0.0)
        .and_then(|s| Duration::try_from_secs_f64(s).ok())
        .ok_or_else(|| CliError::Usage(format!("--for {seconds}: must be > 0 s")))?;
    let velocity = if rates {
        let n = joint_count(cli, client)?;
        if values.len() != n {
            return Err(CliError::Usage(format!(
                "{} joint rates, but the arm has {n} joints",
                values.len()
            )));
        }
        Velocity::Joints(values.to_vec())
    } else {
        let (linear, angular) = match values {
            [x, y, z] => ([*x, *y, *z], [0.0; 3]),
            [x, y, z, a, b, c] => ([*x, *y, *z], [*a, *b, *c]),
            _ => {
                return Err(CliError::Usage(format!(
                    "{} values: a twist is vx vy vz (m/s), optionally wx wy wz (rad/s)",
                    values.len()
                )));
            }
        };
        let frame = if tool {
            TwistFrame::Tool
        } else {
            TwistFrame::Base
        };
        Velocity::Twist {
            linear,
            angular,
            frame,
        }
    };
    // Ctrl-C ends the stream early: the arm ramps to rest as when it ends.
    let interrupt = interrupt::ctrl_c().ok();
    let interrupted = || interrupt.as_ref().is_some_and(interrupt::Interrupt::is_set);
    let started = std::time::Instant::now();
    match client.stream_for(&velocity, duration, interrupted) {
        Ok(sent) => writeln!(
            out,
            "streamed {sent} commands over {:.2} s; the arm ramps to rest",
            started.elapsed().as_secs_f64()
        )?,
        Err(ClientError::Interrupted) => {
            return Err(CliError::Interrupted(
                "stopped streaming: the arm ramps to rest".to_owned(),
            ));
        }
        Err(e) => return Err(e.into()),
    }
    // Why the arm held where the stream would have driven it on (`WN12 jN at limit L`, `WN13`),
    // said here rather than only on stderr: otherwise a jog at a limit looks like nothing.
    let _ = client.poll_notices();
    for notice in client.take_notices() {
        writeln!(out, "notice: {notice}")?;
    }
    settle(client)?;
    writeln!(out, "at rest")?;
    Ok(())
}

/// `armgate on`: ON, then wait until the drives run.
fn drives_on(client: &mut Client, timeout: Duration, out: &mut impl Write) -> Result<(), CliError> {
    match client.start_drives(timeout)? {
        DrivesOn::Started(after) => writeln!(out, "drives running ({:.2} s)", after.as_secs_f64())?,
        DrivesOn::AlreadyRunning(after) => {
            writeln!(out, "drives already running ({:.2} s)", after.as_secs_f64())?
        }
        DrivesOn::Unconfirmed(why) => writeln!(out, "drives on (not confirmed: {why})")?,
    }
    Ok(())
}

/// After a wait: how long to wait until the motion has ended (see [`Client::wait_motion_ended`]).
const SETTLE: Duration = Duration::from_secs(5);

/// After a wait: until the motion has ended.
fn settle(client: &mut Client) -> Result<(), CliError> {
    Ok(client.wait_motion_ended(SETTLE)?)
}

fn print_notices(client: &mut Client) {
    let _ = client.poll_notices();
    for notice in client.take_notices() {
        eprintln!("notice: {notice}");
    }
}

fn dispatch(cli: &Cli, client: &mut Client, out: &mut impl Write) -> Result<(), CliError> {
    match &cli.command {
        Cmd::Send {
            chars,
            values,
            index,
        } => send(client, chars, values, *index, out),
        Cmd::Status => {
            let mut status = client.status()?;
            status.cause = client.stop_cause()?;
            writeln!(out, "{status}")?;
            if cli.key.is_some() {
                let s = client.signing_report()?;
                writeln!(
                    out,
                    "signing    {} signed, {} unsigned served; dropped {} unsigned, {} truncated, \
                     {} forged, {} replayed",
                    s.signed,
                    s.unsigned,
                    s.dropped_unsigned,
                    s.dropped_truncated,
                    s.dropped_forged,
                    s.dropped_replayed
                )?;
            }
            Ok(())
        }
        Cmd::Pose => print_pose(&client.pose()?, out),
        Cmd::Joints => {
            let n = joint_count(cli, client)?;
            let q = client.joints(n)?;
            writeln!(out, "joints (rad; m for prismatic joints)")?;
            for (k, v) in q.iter().enumerate() {
                writeln!(out, "  q{:<2} {v:>10.6}", k + 1)?;
            }
            Ok(())
        }
        Cmd::Temps => {
            let n = joint_count(cli, client)?;
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
        Cmd::On { wait_timeout } => drives_on(client, *wait_timeout, out),
        Cmd::Off => match client.off() {
            // `ER10 Arm already off` / `already stopping`: what was asked for.
            Err(ClientError::Rejected(text)) if drives::already_stopped(&text).is_some() => {
                let state = drives::already_stopped(&text).unwrap_or_default();
                writeln!(out, "drives already {state}")?;
                Ok(())
            }
            result => ok(result, "drives off", out),
        },
        Cmd::Stop => ok(client.stop(), "stopped", out),
        Cmd::Jog {
            values,
            seconds,
            tool,
            rates,
        } => jog(cli, client, values, *seconds, (*tool, *rates), out),
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
            let interrupt = wait.interrupt();
            client.goal_rpy(xyz, rpy, *time)?;
            start(client, Client::begin)?;
            writeln!(out, "moving")?;
            if wait.no_wait {
                return Ok(());
            }
            let goal = Pose::from_xyz_rpy(xyz, rpy);
            let options = wait.options(*time, interrupt.as_ref());
            let pose = follow(client, |c| {
                c.wait_until_pose(&goal, &options, pose_progress)
            })?;
            writeln!(
                out,
                "arrived: {} ({:.2} mm from the goal)",
                fmt_values(&pose.xyz, 4),
                pose.distance(&goal) * 1e3
            )?;
            Ok(())
        }
        Cmd::Ik { pose } => {
            let (xyz, rpy) = pose.xyz_rpy();
            let Some(solutions) = client.ik_solutions(xyz, rpy)? else {
                writeln!(out, "no closed-form IK for this robot (docs/kinematics.md)")?;
                return Ok(());
            };
            writeln!(
                out,
                "{} solutions (branch: shoulder 1, elbow 2, wrist 4)",
                solutions.len()
            )?;
            for s in &solutions {
                writeln!(out, "  branch {} {}", s.branch, fmt_values(&s.q, 6))?;
            }
            Ok(())
        }
        Cmd::IkMove {
            pose,
            branch,
            time,
            wait,
        } => {
            let (xyz, rpy) = pose.xyz_rpy();
            let interrupt = wait.interrupt();
            let goal = start(client, |c| c.ik_move(xyz, rpy, *branch, *time))?;
            writeln!(
                out,
                "moving to {} (branch {})",
                fmt_values(&goal.q, 4),
                goal.branch
            )?;
            if wait.no_wait {
                return Ok(());
            }
            let options = wait.options(*time, interrupt.as_ref());
            let reached = follow(client, |c| {
                c.wait_until_joints(&goal.q, &options, joint_progress)
            })?;
            writeln!(out, "arrived: {}", fmt_values(&reached, 4))?;
            Ok(())
        }
        Cmd::Jmove { q, time, wait } => {
            check_joint_count(q.len(), joint_count(cli, client)?)?;
            let interrupt = wait.interrupt();
            match time {
                None => {
                    client.joint_goal(q)?;
                    start(client, Client::joint_begin)?;
                }
                Some(t) => {
                    client.joint_via_clear()?;
                    client.via_joint(0, q, *t)?;
                    start(client, Client::run_joint_sequence)?;
                }
            }
            writeln!(out, "moving")?;
            if wait.no_wait {
                return Ok(());
            }
            let options = wait.options(time.unwrap_or(0.0), interrupt.as_ref());
            let reached = follow(client, |c| c.wait_until_joints(q, &options, joint_progress))?;
            writeln!(out, "arrived: {}", fmt_values(&reached, 4))?;
            Ok(())
        }
        Cmd::Run { file, blend, wait } => {
            if let Some(blend) = blend.filter(|b| !(b.is_finite() && *b >= 0.0)) {
                return Err(CliError::Usage(format!(
                    "--blend {blend} must be a number of mm (mrad) ≥ 0"
                )));
            }
            let mut run = RunFile::load(file, joint_count(cli, client)?)?;
            if let Some(blend) = blend {
                run.set_default_blend(blend * 1e-3);
            }
            let interrupt = wait.interrupt();
            start(client, |c| c.start_run(&run))?;
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
                    let options = wait.passing(total, interrupt.as_ref(), run.largest_blend());
                    let pose = follow(client, |c| {
                        c.wait_through_poses(&goals, &options, pose_progress)
                    })?;
                    writeln!(out, "done: {}", fmt_values(&pose.xyz, 4))?;
                }
                RunFile::Joint(points) => {
                    let total = points.iter().map(|p| p.time).sum();
                    let goals: Vec<Vec<f64>> = points.iter().map(|p| p.q.clone()).collect();
                    let options = wait.passing(total, interrupt.as_ref(), run.largest_blend());
                    let q = follow(client, |c| {
                        c.wait_through_joints(&goals, &options, joint_progress)
                    })?;
                    writeln!(out, "done: {}", fmt_values(&q, 4))?;
                }
            }
            Ok(())
        }
        // Handled in `run`: teleop takes the client over; calibrate, urdf, record and plot need none.
        Cmd::Teleop { .. }
        | Cmd::Calibrate { .. }
        | Cmd::Urdf { .. }
        | Cmd::Record { .. }
        | Cmd::Plot(_) => Ok(()),
    }
}

fn check_joint_count(given: usize, joints: usize) -> Result<(), CliError> {
    if given == joints {
        Ok(())
    } else {
        Err(CliError::Usage(format!(
            "{given} joint values, but the arm has {joints} joints (--joints overrides)"
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
    use crate::fake::{FakeController, echo, text};
    use crate::status::tests::status_reply;
    use armgate_protocol::client::{Command, Message, Reply, Request};
    use clap::CommandFactory;
    use std::sync::{Arc, Mutex};

    /// SQ numbers: Cartesian mode, drives running, no fault, 6 joints, idle.
    const RUNNING_CART: [f32; 7] = [2.0, 2.0, 0.0, 6.0, 0.0, 0.0, 1.0];

    #[test]
    fn status_prints_the_state() {
        let fake = FakeController::spawn(|d| {
            vec![status_reply(
                d,
                [1.0, 4.0, 33.0, 8.0, 0.0, 5.0, 9.5],
                "ranger-mk2",
            )]
        });
        let (result, out) = run_with(&fake, &["status"]);
        result.unwrap();
        for line in [
            "robot      ranger-mk2 (8 joints)",
            "mode       joint (1)",
            "drives     faulted (ER33)",
            "refused    5 requests",
        ] {
            assert!(out.contains(line), "{line}: {out}");
        }
        let old = FakeController::spawn(|_| vec![text("ER00 Cmd SQ not understood")]);
        let (result, _) = run_with(&old, &["status"]);
        assert!(result.unwrap_err().to_string().contains("too old"));
    }

    /// A controller whose drives start when ON arrives and run after `polls` status polls;
    /// ON while they start or run is `ER11`.
    fn booting(polls: usize, fault: bool) -> FakeController {
        let state = Arc::new(Mutex::new((0.0f32, 0usize)));
        FakeController::spawn(move |d| {
            let mut s = state.lock().unwrap();
            match &d[..2] {
                b"ON" if s.0 == 0.0 || s.0 == 4.0 => {
                    *s = (1.0, 0);
                    vec![echo(d)]
                }
                b"ON" => vec![text("ER11 Arm did not start")],
                _ => {
                    if d[30] == 0 && s.0 == 1.0 {
                        s.1 += 1;
                        if s.1 > polls {
                            s.0 = if fault { 4.0 } else { 2.0 };
                        }
                    }
                    let fault_code = if s.0 == 4.0 { 31.0 } else { 0.0 };
                    vec![status_reply(
                        d,
                        [0.0, s.0, fault_code, 6.0, 0.0, 0.0, 1.0],
                        "r",
                    )]
                }
            }
        })
    }

    #[test]
    fn on_waits_until_the_drives_run() {
        let fake = booting(3, false);
        let (result, out) = run_with(&fake, &["on"]);
        result.unwrap();
        assert!(out.starts_with("drives running ("), "{out}");
        // ON again: ER11, but they run, so that is success.
        let (result, out) = run_with(&fake, &["on"]);
        result.unwrap();
        assert!(out.starts_with("drives already running"), "{out}");
        let faulty = booting(2, true);
        let (result, _) = run_with(&faulty, &["on"]);
        let err = result.unwrap_err();
        assert_eq!(err.to_string(), "the drives did not start: faulted (ER31)");
        assert_eq!(err.exit_code(), 1);
        let slow = booting(usize::MAX, false);
        let (result, _) = run_with(&slow, &["on", "--wait-timeout", "200ms"]);
        assert!(result.unwrap_err().to_string().contains("still starting"));
    }

    #[test]
    fn on_right_after_off_waits_for_the_drives_to_stop_and_sends_on_again() {
        // Stopping for three status polls; ON is refused until then, and starts them at once.
        let state = Arc::new(Mutex::new((3.0f32, 0usize)));
        let fake = FakeController::spawn(move |d| {
            let mut s = state.lock().unwrap();
            match &d[..2] {
                b"ON" if s.0 == 0.0 => {
                    s.0 = 2.0;
                    vec![echo(d)]
                }
                b"ON" => vec![text("ER11 Arm did not start")],
                _ => {
                    if d[30] == 0 && s.0 == 3.0 {
                        s.1 += 1;
                        if s.1 >= 3 {
                            s.0 = 0.0;
                        }
                    }
                    vec![status_reply(d, [0.0, s.0, 0.0, 6.0, 0.0, 0.0, 1.0], "r")]
                }
            }
        });
        let (result, out) = run_with(&fake, &["on"]);
        result.unwrap();
        assert!(out.starts_with("drives running"), "{out}");
        let ons = fake.received().iter().filter(|d| &d[..2] == b"ON").count();
        assert_eq!(ons, 4);
    }

    #[test]
    fn off_when_already_off_is_no_failure() {
        let fake = FakeController::spawn(|d| match &d[..2] {
            b"OF" => vec![text("ER10 Arm already off")],
            _ => vec![],
        });
        let (result, out) = run_with(&fake, &["off"]);
        result.unwrap();
        assert_eq!(out, "drives already off\n");
        let fake = FakeController::spawn(|d| match &d[..2] {
            b"OF" => vec![text("ER10 Arm stopped by fault")],
            _ => vec![],
        });
        let (result, _) = run_with(&fake, &["off", "--timeout", "50ms"]);
        assert_eq!(result.unwrap_err().to_string(), "ER10 Arm stopped by fault");
    }

    #[test]
    fn a_refusal_with_the_drives_off_hints_at_on() {
        let fake = FakeController::spawn(|d| match &d[..2] {
            b"SQ" => vec![status_reply(d, [2.0, 0.0, 0.0, 6.0, 0.0, 3.0, 1.0], "r")],
            b"BG" => vec![text("ER20 Cmd BG drives off")],
            _ => {
                vec![echo(d)]
            }
        });
        let (result, _) = run_with(&fake, &["move", "0.5", "0.2", "0.1", "0", "0", "0"]);
        let CliError::Refused { text, hint } = result.unwrap_err() else {
            panic!()
        };
        assert_eq!(text.as_str(), "ER20 Cmd BG drives off");
        assert!(hint.unwrap().contains("`armgate on`"));
    }

    #[test]
    fn a_wait_that_fails_sends_st_and_keeps_its_exit_status() {
        let fake = FakeController::spawn(|d| vec![echo(d)]);
        let mut client = Client::connect(fake.addr()).unwrap();
        let err = stop_started(&mut client, ClientError::Interrupted);
        assert_eq!(
            err.to_string(),
            "interrupted: sent ST: the arm stops and holds"
        );
        assert_eq!(err.exit_code(), 130);
        assert_eq!(&fake.received()[0][..2], b"ST");
        let timeout = ClientError::WaitTimeout {
            target: 0,
            distance: 0.25,
            angle: None,
            timeout: Duration::from_secs(1),
        };
        let err = stop_started(&mut client, timeout);
        assert_eq!(
            err.to_string(),
            "target 1 not reached within 1s (still 0.2500 (joint norm) from it); sent ST: the arm \
             stops and holds"
        );
        assert_eq!(err.exit_code(), 2);
        let err = stop_started(
            &mut client,
            ClientError::Aborted(crate::fake::parsed_text("WN22 Inv Kin Divergence.")),
        );
        assert_eq!(err.exit_code(), 1);
        assert_eq!(fake.received().len(), 3);
        assert!(fake.received().iter().all(|d| &d[..2] == b"ST"));
    }

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
        assert_eq!(cli.joints, Some(8));
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
        assert!(parse_timeout("0").is_err());
        assert!(parse_timeout("0ms").is_err());
        assert_eq!(parse_timeout("1ms"), Ok(Duration::from_millis(1)));
        assert!(Cli::try_parse_from(["armgate", "--timeout", "0s", "pose"]).is_err());
        // The mode as the status shows it, and as the help numbers it, is accepted too.
        for (typed, mode) in [
            ("cartesian", ModeArg::Cart),
            ("2", ModeArg::Cart),
            ("1", ModeArg::Joint),
            ("0", ModeArg::Off),
        ] {
            let cli = Cli::try_parse_from(["armgate", "mode", typed]).unwrap();
            assert!(
                matches!(cli.command, Cmd::Mode { mode: m } if m == mode),
                "{typed}"
            );
        }
        assert!(Cli::try_parse_from(["armgate", "mode", "3"]).is_err());
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
                vec![echo(d)]
            } else {
                vec![]
            }
        });
        let (result, _) = run_with(&fake, &["stop", "--timeout", "50ms", "--retries", "0"]);
        assert_eq!(result.unwrap_err().exit_code(), 2);
        let (result, _) = run_with(&fake, &["move", "0.5", "0.2", "0.1", "0", "0", "0"]);
        let err = result.unwrap_err();
        assert_eq!(err.exit_code(), 1);
        let CliError::Refused { text, hint } = err else {
            panic!()
        };
        assert_eq!(text.as_str(), "ER20 Cmd BG rejected");
        // No status from this fake: the hint lists what BG needs.
        assert!(hint.unwrap().contains("mode cart"));
    }

    #[test]
    fn a_begin_without_a_reply_may_have_started_the_motion_and_is_stopped() {
        let fake = FakeController::spawn(|d| match &d[..2] {
            b"BG" => vec![],
            _ => vec![echo(d)],
        });
        let args = ["move", "0.5", "0.2", "0.1", "0", "0", "0"];
        let retry = ["--timeout", "50ms", "--retries", "1"];
        let (result, _) = run_with(&fake, &[&args[..], &retry].concat());
        let err = result.unwrap_err();
        assert_eq!(err.exit_code(), 2);
        assert!(
            err.to_string()
                .ends_with("; sent ST: the arm stops and holds"),
            "{err}"
        );
        let sent: Vec<_> = fake.received().iter().map(|d| d[..2].to_vec()).collect();
        assert_eq!(sent, [b"GT", b"BG", b"BG", b"ST"]);
    }

    #[test]
    fn jmove_with_a_time_uses_a_via_point() {
        let fake = cartesian_controller(|r, reply| {
            if r.command == Command::JointPosition {
                reply.values = [0.0, 0.5, 1.0, 0.0, 0.3, 0.0, 0.0];
            }
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
            .filter(|c| c != "WD")
            .collect();
        // The joint count comes from the status (SQ twice: numbers and name); the wait's
        // watchdog (WD) left out.
        assert_eq!(sent[..5], ["SQ", "SQ", "jC", "jV", "jE"]);
        // Then jP until arrival, and SQ until the motion has ended.
        let polls = &sent[5..];
        let first_sq = polls.iter().position(|c| c == "SQ").unwrap();
        assert!(polls[..first_sq].iter().all(|c| c == "jP"), "{polls:?}");
        assert!(polls[first_sq..].iter().all(|c| c == "SQ"), "{polls:?}");
        let (result, _) = run_with(&fake, &["jmove", "0", "0.5"]);
        let err = result.unwrap_err();
        assert_eq!(err.exit_code(), 2);
        assert!(err.to_string().contains("the arm has 6 joints"), "{err}");
        // --joints overrides the status.
        let before = fake.received().len();
        let (result, _) = run_with(&fake, &["--joints", "2", "jmove", "0", "0.5", "--no-wait"]);
        result.unwrap();
        assert_eq!(fake.received()[before..][0][..2], *b"jG");
    }

    /// A ranger-mk1 running in Cartesian mode: the status `RUNNING_CART`, and to any other
    /// request the null reply with the request's index, as `answer` fills it in.
    fn cartesian_controller(
        answer: impl Fn(&Request, &mut Reply) + Send + 'static,
    ) -> FakeController {
        FakeController::spawn(move |d| {
            if &d[..2] == b"SQ" {
                return vec![status_reply(d, RUNNING_CART, "ranger-mk1")];
            }
            let m = Message::new_checked(d).unwrap();
            let r = Request::parse(&m).unwrap();
            let mut reply = Reply::null(r.command);
            reply.index = r.index;
            answer(&r, &mut reply);
            vec![reply.to_bytes().to_vec()]
        })
    }

    /// A controller in Cartesian mode whose tool sits at (0.5, 0.2, 0.1): replies echo the
    /// index and f0 (as `TV` does).
    fn run_controller() -> FakeController {
        cartesian_controller(|r, reply| {
            reply.values[0] = r.values[0];
            if r.command == Command::Pose {
                reply.values = [0.5, 0.2, 0.1, 0.0, 0.0, 0.0, 1.0];
            }
        })
    }

    #[test]
    fn run_loads_the_file_into_via_slots() {
        let fake = run_controller();
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
        assert_eq!(chars[..6], [b"SQ", b"SQ", b"VC", b"VP", b"VP", b"VE"]);
        assert_eq!(sent[3][30], 0);
        assert_eq!(sent[4][30], 1);
    }

    #[test]
    fn run_with_blend_sends_a_tolerance_per_slot() {
        let fake = run_controller();
        let file = std::env::temp_dir().join(format!("armgate-blend-{}.toml", std::process::id()));
        std::fs::write(
            &file,
            "[[cartesian]]\nxyz = [0.5, 0.2, 0.1]\nrpy = [0, 0, 0]\nblend = 0.01\n\
             [[cartesian]]\nxyz = [0.5, 0.2, 0.1]\nrpy = [0, 0, 0]\n",
        )
        .unwrap();
        let args = ["run", file.to_str().unwrap(), "--blend", "2"];
        let (result, _) = run_with(&fake, &args);
        std::fs::remove_file(&file).unwrap();
        result.unwrap();
        let sent = fake.received();
        let chars: Vec<&[u8]> = sent.iter().map(|d| &d[..2]).collect();
        assert_eq!(
            chars[..7],
            [b"SQ", b"SQ", b"VC", b"VP", b"VT", b"VP", b"VT"]
        );
        // Slot 0 keeps its own 0.01 m, slot 1 gets --blend 2 mm, as f0 (f32, little-endian).
        assert_eq!(sent[4][2..6], 0.01f32.to_le_bytes());
        assert_eq!(sent[4][30], 0);
        assert_eq!(sent[6][2..6], 0.002f32.to_le_bytes());
        assert_eq!(sent[6][30], 1);
        let (result, _) = run_with(&fake, &["run", "x.toml", "--blend=-1"]);
        let error = result.unwrap_err().to_string();
        assert!(error.contains("--blend -1 must be"), "{error}");
    }
}
