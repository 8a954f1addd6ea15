//! The subcommands that change the controller's state: `mode`, `on`, `off`, `stop`.

use std::io::Write;
use std::time::Duration;

use clap::{Args, ValueEnum};

use super::CliError;
use super::options::parse_duration;
use crate::{Client, ClientError, DrivesOn, Mode};

/// `armgate mode` arguments.
#[derive(Debug, Args)]
pub struct ModeArgs {
    /// off (0), joint (1) or cart (2).
    pub mode: ModeArg,
}

/// `armgate on` arguments.
#[derive(Debug, Args)]
pub struct OnArgs {
    /// Give up waiting for the drives after this long.
    #[arg(long, default_value = "5s", value_parser = parse_duration)]
    pub wait_timeout: Duration,
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

/// `armgate mode`: CM, and the mode the controller reports.
pub(super) fn mode(
    args: &ModeArgs,
    client: &mut Client,
    out: &mut impl Write,
) -> Result<(), CliError> {
    let ModeArgs { mode } = args;
    let reported = client.set_mode((*mode).into())?;
    writeln!(out, "mode {} ({})", reported.name(), reported.value())?;
    Ok(())
}

/// `armgate on`: ON, then wait until the drives run.
pub(super) fn on(args: &OnArgs, client: &mut Client, out: &mut impl Write) -> Result<(), CliError> {
    match client.start_drives(args.wait_timeout)? {
        DrivesOn::Started(after) => writeln!(out, "drives running ({:.2} s)", after.as_secs_f64())?,
        DrivesOn::AlreadyRunning(after) => {
            writeln!(out, "drives already running ({:.2} s)", after.as_secs_f64())?
        }
        DrivesOn::Unconfirmed(why) => writeln!(out, "drives on (not confirmed: {why})")?,
    }
    Ok(())
}

/// `armgate off`: OF; drives that are off (or stopping) already are what was asked for.
pub(super) fn off(client: &mut Client, out: &mut impl Write) -> Result<(), CliError> {
    match client.off() {
        // `ER10 Arm already off` / `already stopping`: what was asked for.
        Err(ClientError::Rejected(text)) if crate::drives::already_stopped(&text).is_some() => {
            let state = crate::drives::already_stopped(&text).unwrap_or_default();
            writeln!(out, "drives already {state}")?;
            Ok(())
        }
        result => ok(result, "drives off", out),
    }
}

/// `armgate stop`.
pub(super) fn stop(client: &mut Client, out: &mut impl Write) -> Result<(), CliError> {
    ok(client.stop(), "stopped", out)
}

fn ok(result: Result<(), ClientError>, what: &str, out: &mut impl Write) -> Result<(), CliError> {
    result?;
    writeln!(out, "{what}")?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::testing::run_with;
    use crate::fake::{FakeController, echo, text};
    use crate::status::tests::status_reply;
    use std::sync::{Arc, Mutex};

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
}
