//! `armgate teleop`: starts the keyboard client (crate::teleop) on this command line's
//! controller.

use std::time::Duration;

use clap::Args;

use super::{Cli, CliError, joint_count};
use crate::Client;
use crate::teleop::{self, TeleopOptions};

/// `armgate teleop --help`: the keys.
pub(super) const TELEOP_LONG: &str = "\
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
  c              desired <- current
  Enter          GT (desired position, current roll/pitch/yaw, T = 0) + BG;
                 joint keys: jG + jB.
                 If BG (jB) is refused, e.g. a motion still runs: ST, then BG (jB) once more.
  j              switch between Cartesian and joint keys
  m              CM to the mode the keys need (cartesian, or joint for the joint keys);
                 in it already: on along off -> joint -> cart -> off
  v              jog keys <-> step keys
  space          stop (ST); a jog key still held does not move again until pressed anew
  o              drives on (ON)
  q, Esc         quit: ST unless another client holds the arm (the terminal is restored);
                 Ctrl-C the same, exit status 130

A Cartesian step is 1 mm x scale, a joint step 0.01 rad x scale.";

/// `armgate teleop` arguments.
#[derive(Debug, Args)]
pub struct TeleopArgs {
    /// Send on every key press instead of on Enter (step keys).
    #[arg(long)]
    pub live: bool,
    /// Keys step the desired values (the seed's teleop) instead of jogging while held.
    #[arg(long)]
    pub step: bool,
    /// How often to read PS, jP and TM (Hz).
    #[arg(long, default_value_t = 10.0)]
    pub rate: f64,
}

/// Runs the keyboard client until the user quits; it takes the client over.
pub(super) fn run(args: &TeleopArgs, cli: &Cli, mut client: Client) -> Result<(), CliError> {
    let TeleopArgs { live, step, rate } = args;
    let poll = Some(1.0 / rate)
        .filter(|p| p.is_finite() && *p > 0.0)
        .and_then(|p| Duration::try_from_secs_f64(p).ok())
        .ok_or_else(|| CliError::Usage(format!("--rate {rate}: must be > 0")))?;
    let options = TeleopOptions {
        joints: joint_count(cli, &mut client)?,
        live: *live,
        jog: !*step,
        poll,
        addr: cli.controller.addr.clone(),
    };
    match teleop::run(client, options).map_err(CliError::Output)? {
        teleop::Ended::Quit => Ok(()),
        teleop::Ended::Interrupted => Err(CliError::Interrupted(
            "teleop ended (ST sent unless another client holds the arm)".to_owned(),
        )),
    }
}
