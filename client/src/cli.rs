//! The `armgate` command line: the options every controller command shares, the subcommands
//! (one module per subcommand or group of them) and a thin dispatch.

mod controller;
mod drives;
mod error;
mod ik;
mod jog;
mod motion;
mod options;
mod output;
mod read;
mod run_file;
mod send;
mod teleop;
#[cfg(test)]
mod testing;
mod tools;

use clap::{Parser, Subcommand};
use std::io::Write;

use crate::hints;
use crate::{Client, ClientConfig, ClientError};

pub use controller::ControllerArgs;
pub use drives::{ModeArg, ModeArgs, OnArgs};
pub use error::CliError;
pub use ik::{IkArgs, IkMoveArgs};
pub use jog::JogArgs;
pub use motion::{JmoveArgs, MoveArgs};
pub use options::{PoseArgs, WaitArgs, parse_duration, parse_seconds, parse_timeout};
pub use read::print_pose;
pub use run_file::RunArgs;
pub use send::SendArgs;
pub use teleop::TeleopArgs;

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

A move, ik-move, jmove or run that fails after starting its motion (Ctrl-C, --wait-timeout,
a stall, no reply) sends ST first and says so: the arm stops and holds. A motion stopped by
the controller or another client says why and by whom.
Unsolicited ER/WN notices that arrive meanwhile are printed to stderr.
";

/// The examples, then the exit statuses (one table, [`crate::exit`]).
fn after_help() -> String {
    format!("{AFTER_HELP}\n{}", crate::exit::help())
}

/// The `armgate` command line: how to reach the controller, and what to do.
#[derive(Debug)]
pub struct Cli {
    /// The controller options, as given before the subcommand and overridden by those after it.
    pub controller: ControllerArgs,
    /// What to do.
    pub command: Cmd,
}

/// The command line as clap derives it: [`Cli`] adds the controller options to the
/// subcommands that use them.
#[derive(Debug, Parser)]
#[command(name = "armgate", version, about = ABOUT, long_about = LONG_ABOUT, after_help = after_help())]
struct Parsed {
    /// How to reach the controller.
    #[command(flatten)]
    controller: ControllerArgs,
    /// What to do.
    #[command(subcommand)]
    command: Cmd,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Cmd {
    /// Send any request and print the reply: its characters, 7 floats and the index, or the
    /// ER/WN text (the seed's text client).
    #[command(after_help = "Example: armgate send GT 0 0.2 0.8 0 0 -1.5708 5")]
    Send(SendArgs),
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
    Mode(ModeArgs),
    /// Start the drives (ON; also clears a drive fault) and wait until they run (SQ).
    On(OnArgs),
    /// Stop the drives (OF).
    Off,
    /// Stop every motion and sequence; the arm holds its position (ST).
    Stop,
    /// Move the tool to a pose (GT + BG, Cartesian mode) and wait until it is within the
    /// tolerance (1 mm, 0.01 rad), showing the remaining distance.
    #[command(after_help = "Example: armgate move 0 0.2 0.8 0 0 -1.5708 --time 5")]
    Move(MoveArgs),
    /// Print every inverse-kinematics solution of a pose within the joint limits, each with
    /// its configuration branch (KS; robots with a closed form, docs/kinematics.md); on a 7–8
    /// joint arm those for the present θ3 (θ5), or for --theta3 (--theta5).
    #[command(
        after_help = "Examples: armgate ik 0 0.2 0.8 0 0 -1.5708\n          armgate ik --theta3 0.5 0.4 0.1 0.6 3.1416 0 0   (iiwa14)"
    )]
    Ik(IkArgs),
    /// Move the joints (joint mode) to the inverse kinematics of a pose on a chosen
    /// configuration branch, or the solution nearest the present joints (KG), and wait; on a
    /// 7–8 joint arm with the present θ3 (θ5), or --theta3 (--theta5).
    #[command(
        after_help = "Examples: armgate ik-move 0 0.2 0.8 0 0 -1.5708\n          armgate ik-move --theta3 0.5 0.4 0.1 0.6 3.1416 0 0   (iiwa14)"
    )]
    IkMove(IkMoveArgs),
    /// Move the joints (joint mode) and wait until within the tolerance (1 mrad).
    ///
    /// Without --time: jG + jB, a minimum-time motion. With --time T: jC, jV slot 0 with T, jE,
    /// since jB takes no duration (this clears the joint via points).
    #[command(after_help = "Example: armgate jmove 1.5708 0.4 1.2 0 1.2 0")]
    Jmove(JmoveArgs),
    /// Stream a velocity for a while, then let the arm ramp to rest: a tool twist (TW,
    /// Cartesian mode: vx vy vz in m/s, optionally wx wy wz in rad/s, base frame unless
    /// --tool) or, with --rates, one rate per joint (jW, joint mode: rad/s).
    #[command(after_help = "Example: armgate jog 0 0 -0.01 --for 1")]
    Jog(JogArgs),
    /// Run a via-point sequence from a TOML file and wait until its last point is reached.
    #[command(long_about = run_file::RUN_LONG)]
    Run(RunArgs),
    /// The keyboard client: live pose, joints and temperatures; move with the arrow keys.
    #[command(long_about = teleop::TELEOP_LONG)]
    Teleop(TeleopArgs),
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
    /// Record this controller into an MCAP file for Foxglove (runs `armgate-viz record`, with
    /// the --addr, --key and --link-id given before `record`; docs/visualisation.md): jP and PS
    /// at --rate, SQ once a second, every notice.
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

/// Runs the command line (parsed from the process's arguments) and returns the exit status.
pub fn main() -> u8 {
    let cli = Cli::parse();
    if let Some(status) = tools::run(&cli.command) {
        return status;
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
            if matches!(e, CliError::Client(ClientError::Timeout { .. }))
                && cli.controller.key.is_none()
            {
                eprintln!(
                    "hint: a controller with a signing key never answers unsigned requests: \
                     --key FILE (or ARMGATE_KEY_FILE)"
                );
            } else if matches!(e, CliError::Client(ClientError::Timeout { .. })) {
                eprintln!(
                    "hint: a controller never answers a request signed with another key, or \
                     for another controller id: is it running, or has it another key? (One \
                     that has just restarted refuses signed requests other than stops for up \
                     to 2 s; they were resent for that long.)"
                );
            }
            e.exit_code()
        }
    }
}

/// Learns the controller's id and a free link id if they are not given, and says on stderr
/// which arm the signed requests are for and on which link (a key may be shared by several
/// arms, and a link id by mistake by several clients).
fn say_which_arm(client: &mut Client) -> Result<(), CliError> {
    if client.signer().is_some_and(crate::Signer::needs_identity) {
        client.identify()?;
    }
    if let Some(signer) = client.signer() {
        eprintln!(
            "armgate: signing for controller {} at {}, link {}",
            signer.controller(),
            client.peer(),
            signer.link()
        );
    }
    Ok(())
}

/// A refusal with its hint, asking the controller's state when it can tell (a refusal of `SQ`
/// itself, or a controller without it, leaves the hint to the text).
fn with_hint(client: &mut Client, error: CliError) -> CliError {
    let CliError::Client(ClientError::Rejected(text)) = error else {
        return error;
    };
    let mut status = client.status().ok();
    if let Some(status) = status.as_mut()
        && crate::matching::code(&text) == Some(40)
    {
        // ER40 has no room for the holder's port: the session report names it.
        status.session = client.session().ok().flatten();
    }
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
        timeout: cli.controller.timeout,
        retries: cli.controller.retries,
        ..ClientConfig::default()
    };
    let mut client = Client::connect_with(cli.controller.addr.as_str(), config)?;
    if let Some(path) = &cli.controller.key {
        let mut signer = crate::Signer::from_file(path, cli.controller.link_id)?;
        if let Some(id) = cli.controller.controller_id {
            signer.set_controller(id);
        }
        client.set_signer(Some(signer));
        say_which_arm(&mut client)?;
    }
    if let Cmd::Teleop(args) = &cli.command {
        return teleop::run(args, cli, client);
    }
    let result = dispatch(cli, &mut client, out).map_err(|e| with_hint(&mut client, e));
    print_notices(&mut client);
    result
}

/// `--joints`, else the joint count the controller reports, else (a controller without `SQ`) 6.
fn joint_count(cli: &Cli, client: &mut Client) -> Result<usize, CliError> {
    if let Some(n) = cli.controller.joints {
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

fn print_notices(client: &mut Client) {
    let _ = client.poll_notices();
    for notice in client.take_notices() {
        eprintln!("notice: {notice}");
    }
}

fn dispatch(cli: &Cli, client: &mut Client, out: &mut impl Write) -> Result<(), CliError> {
    match &cli.command {
        Cmd::Send(args) => send::send(args, client, out),
        Cmd::Status => read::status(cli, client, out),
        Cmd::Pose => read::pose(client, out),
        Cmd::Joints => read::joints(cli, client, out),
        Cmd::Temps => read::temps(cli, client, out),
        Cmd::Mode(args) => drives::mode(args, client, out),
        Cmd::On(args) => drives::on(args, client, out),
        Cmd::Off => drives::off(client, out),
        Cmd::Stop => drives::stop(client, out),
        Cmd::Jog(args) => jog::jog(args, cli, client, out),
        Cmd::Move(args) => motion::move_to(args, client, out),
        Cmd::Ik(args) => {
            let joints = joint_count(cli, client)?;
            ik::ik(args, joints, client, out)
        }
        Cmd::IkMove(args) => ik::ik_move(args, client, out),
        Cmd::Jmove(args) => motion::jmove(args, cli, client, out),
        Cmd::Run(args) => run_file::run(args, cli, client, out),
        // Handled in `run`: teleop takes the client over; calibrate, urdf, record and plot need none.
        Cmd::Teleop { .. }
        | Cmd::Calibrate { .. }
        | Cmd::Urdf { .. }
        | Cmd::Record { .. }
        | Cmd::Plot(_) => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
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
        let Cmd::Move(MoveArgs { pose, time, .. }) = cli.command else {
            panic!()
        };
        assert_eq!((pose.y, pose.yaw, time), (-0.2, -1.25, 4.0));
        let cli = Cli::try_parse_from([
            "armgate", "--joints", "8", "jmove", "-1", "0", "0", "0", "0", "0", "0", "-0.5",
        ])
        .unwrap();
        assert_eq!(cli.controller.joints, Some(8));
        let Cmd::Jmove(JmoveArgs { q, time: None, .. }) = cli.command else {
            panic!()
        };
        assert_eq!(q.len(), 8);
        assert!(Cli::try_parse_from(["armgate", "--joints", "9", "pose"]).is_err());
        let cli =
            Cli::try_parse_from(["armgate", "send", "GT", "0.5", "-0.2", "--index", "3"]).unwrap();
        assert!(
            matches!(cli.command, Cmd::Send(SendArgs { ref values, index: 3, .. }) if values == &[0.5, -0.2])
        );
    }
}
