//! The options several subcommands share: a pose, waiting for a motion, durations.

use std::time::Duration;

use clap::Args;

use crate::banks::MAX_JOINTS;
use crate::{StopPolicy, WaitOptions, interrupt};

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
    pub(super) fn xyz_rpy(&self) -> ([f64; 3], [f64; 3]) {
        ([self.x, self.y, self.z], [self.roll, self.pitch, self.yaw])
    }
}

/// Options of the commands that wait for a motion.
#[derive(Clone, Debug, Args)]
pub struct WaitArgs {
    /// Return as soon as the motion has started.
    #[arg(long)]
    pub no_wait: bool,
    /// Give up waiting after this long, e.g. 90s, 500ms, 2min (a bare number is seconds);
    /// then ST. Default: twice the planned duration the controller reports plus 30 s, else
    /// 10 min plus the requested times (a stalled arm ends the wait after 3 s anyway).
    #[arg(long, value_parser = parse_duration)]
    pub wait_timeout: Option<Duration>,
    /// Arrival tolerance, mm (joints: mrad); more than 0 (the measured values are floats: an
    /// exact arrival is never seen).
    #[arg(long, default_value_t = 1.0, value_parser = parse_tolerance)]
    pub tolerance: f64,
    /// On Ctrl-C exit and leave the arm moving, saying so (by default ST is sent first).
    #[arg(long)]
    pub no_stop_on_interrupt: bool,
}

impl WaitArgs {
    /// The wait's options for a motion that takes at least `requested` s, or `planned` as the
    /// controller reports it; with `interrupt`, Ctrl-C ends the wait.
    pub(super) fn options(
        &self,
        requested: f64,
        planned: Option<Duration>,
        interrupt: Option<&interrupt::Interrupt>,
    ) -> WaitOptions {
        let extra = Duration::try_from_secs_f64(requested).unwrap_or_default();
        let default = match planned {
            // Room for slow-downs near singularities and joint limits.
            Some(planned) => planned.saturating_mul(2).saturating_add(PLANNED_MARGIN),
            None => WaitOptions::default().timeout.saturating_add(extra),
        };
        WaitOptions {
            tolerance: self.tolerance * 1e-3,
            timeout: self.wait_timeout.unwrap_or(default),
            interrupt: interrupt.cloned(),
            stop: if self.no_stop_on_interrupt {
                StopPolicy::ExceptInterrupt
            } else {
                StopPolicy::Always
            },
            ..WaitOptions::default()
        }
    }

    /// The options of a wait through via points blended within `blend`: an intermediate
    /// point counts as passed within the blend plus the usual pass tolerance.
    pub(super) fn passing(
        &self,
        requested: f64,
        interrupt: Option<&interrupt::Interrupt>,
        blend: f64,
    ) -> WaitOptions {
        let options = self.options(requested, None, interrupt);
        WaitOptions {
            pass_tolerance: options.pass_tolerance + blend,
            ..options
        }
    }

    /// Installs the Ctrl-C handler (unless there is no wait to interrupt): the wait ends and
    /// says what the arm does ([`WaitOptions::stop`]). Installed before the first request, so
    /// that Ctrl-C while the motion is being started stops it as well.
    pub(super) fn interrupt(&self) -> Option<interrupt::Interrupt> {
        if self.no_wait {
            return None;
        }
        interrupt::ctrl_c()
            .map_err(|e| eprintln!("armgate: {e}; Ctrl-C will not stop the arm"))
            .ok()
    }
}

/// The margin of a wait on a motion whose planned duration the controller reported.
const PLANNED_MARGIN: Duration = Duration::from_secs(30);

/// Parses a duration with its unit, `200ms`, `1.5s`, `2min`, or a bare number of seconds (as
/// every duration of the `armgate` tool: `--timeout`, `--wait-timeout`, `--time`, `--for`).
pub fn parse_duration(s: &str) -> Result<Duration, String> {
    let s = s.trim();
    let (number, scale) = if let Some(ms) = s.strip_suffix("ms") {
        (ms, 1e-3)
    } else if let Some(min) = s.strip_suffix("min") {
        (min, 60.0)
    } else if let Some(secs) = s.strip_suffix('s') {
        (secs, 1.0)
    } else {
        (s, 1.0)
    };
    number
        .trim()
        .parse::<f64>()
        .ok()
        .and_then(|v| Duration::try_from_secs_f64(v * scale).ok())
        .ok_or_else(|| format!("`{s}` is not a duration (e.g. 200ms, 1.5s, 2min; bare: seconds)"))
}

/// A duration in seconds, for the options that are numbers of seconds (`--time`, `--for`).
pub fn parse_seconds(s: &str) -> Result<f64, String> {
    parse_duration(s).map(|d| d.as_secs_f64())
}

/// An arrival tolerance: finite and more than 0 (`--tolerance 0` could never be met and would
/// end every wait as a stall).
fn parse_tolerance(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!(
            "`{s}`: the tolerance is a number of mm (joints: mrad) above 0, e.g. 0.1"
        )),
    }
}

/// A duration that is not zero: a zero reply timeout would never wait for a reply.
pub fn parse_timeout(s: &str) -> Result<Duration, String> {
    match parse_duration(s)? {
        Duration::ZERO => Err(format!("`{s}`: the timeout must be longer than 0")),
        timeout => Ok(timeout),
    }
}

pub(super) fn parse_joints(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(n) if (1..=MAX_JOINTS).contains(&n) => Ok(n),
        _ => Err(format!("`{s}`: the number of joints is 1 to {MAX_JOINTS}")),
    }
}

#[cfg(test)]
mod tests {
    use super::super::drives::{ModeArg, ModeArgs};
    use super::super::{Cli, Cmd};
    use super::*;
    use clap::Parser;

    #[test]
    fn durations() {
        assert_eq!(parse_duration("200ms"), Ok(Duration::from_millis(200)));
        assert_eq!(parse_duration("1.5s"), Ok(Duration::from_millis(1500)));
        // The wait: twice the planned duration plus 30 s, else 10 min plus the requested time;
        // --wait-timeout wins.
        let cli = Cli::try_parse_from(["armgate", "jmove", "0"]).unwrap();
        let Cmd::Jmove(args) = cli.command else {
            panic!()
        };
        let planned = Some(Duration::from_secs(45));
        assert_eq!(
            args.wait.options(0.0, planned, None).timeout,
            Duration::from_secs(120)
        );
        assert_eq!(
            args.wait.options(5.0, None, None).timeout,
            Duration::from_secs(605)
        );
        let cli = Cli::try_parse_from(["armgate", "jmove", "0", "--wait-timeout", "2s"]).unwrap();
        let Cmd::Jmove(args) = cli.command else {
            panic!()
        };
        assert_eq!(
            args.wait.options(0.0, planned, None).timeout,
            Duration::from_secs(2)
        );
        assert!(Cli::try_parse_from(["armgate", "jmove", "0", "--tolerance", "0"]).is_err());
        assert!(Cli::try_parse_from(["armgate", "jmove", "0", "--tolerance", "0.05"]).is_ok());
        // A bare number is seconds, as --time and --for are (issue 37: 90 was 90 ms).
        assert_eq!(parse_duration("90"), Ok(Duration::from_secs(90)));
        assert_eq!(parse_duration("2min"), Ok(Duration::from_secs(120)));
        assert_eq!(parse_seconds("500ms"), Ok(0.5));
        let cli = Cli::try_parse_from(["armgate", "jmove", "0", "--wait-timeout", "90"]).unwrap();
        let Cmd::Jmove(args) = cli.command else {
            panic!()
        };
        assert_eq!(args.wait.wait_timeout, Some(Duration::from_secs(90)));
        let cli = Cli::try_parse_from([
            "armgate", "move", "0", "0", "0", "0", "0", "0", "--time", "1.5s",
        ])
        .unwrap();
        assert!(matches!(cli.command, Cmd::Move(m) if m.time == 1.5));
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
                matches!(cli.command, Cmd::Mode(ModeArgs { mode: m }) if m == mode),
                "{typed}"
            );
        }
        assert!(Cli::try_parse_from(["armgate", "mode", "3"]).is_err());
    }
}
