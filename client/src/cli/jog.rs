//! `armgate jog`: stream a twist (TW) or joint rates (jW) for a while, then ramp to rest.

use std::io::Write;
use std::time::Duration;

use clap::Args;

use super::output::settle;
use super::{Cli, CliError, joint_count};
use crate::banks::MAX_JOINTS;
use crate::{Client, ClientError, TwistFrame, Velocity, interrupt};

/// `armgate jog` arguments.
#[derive(Debug, Args)]
pub struct JogArgs {
    /// The twist (3 or 6 values) or the joint rates (one per joint).
    #[arg(required = true, num_args = 1..=MAX_JOINTS, allow_negative_numbers = true)]
    pub values: Vec<f64>,
    /// How long to stream (`1`, `1s`, `500ms`; bare: seconds).
    #[arg(long = "for", default_value_t = 1.0, value_parser = super::options::parse_seconds)]
    pub seconds: f64,
    /// The twist is in the tool frame.
    #[arg(long, conflicts_with = "rates")]
    pub tool: bool,
    /// The values are joint rates (jW), one per joint.
    #[arg(long)]
    pub rates: bool,
}

/// What a twist beyond the robot's Cartesian speed limits was cut to (the controller's `TW`
/// echo): `jog 0 0 1` says the 1 m/s was clamped, and to what.
fn cut_warning(asked: &[f64], cut: [f64; 6]) -> String {
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let (linear, angular) = (
        norm(asked.get(..3).unwrap_or(&[])),
        norm(asked.get(3..).unwrap_or(&[])),
    );
    let [x, y, z, a, b, c] = cut;
    let speeds = if angular > 0.0 {
        format!(
            "{linear:.3} m/s, {angular:.3} rad/s is beyond the robot's Cartesian speed limits \
             (robot file [cartesian] max_velocity): clamped to {:.3} m/s, {:.3} rad/s",
            norm(&[x, y, z]),
            norm(&[a, b, c])
        )
    } else {
        format!(
            "{linear:.3} m/s is beyond the robot's Cartesian speed limits (robot file \
             [cartesian] max_velocity): clamped to {:.3} m/s",
            norm(&[x, y, z])
        )
    };
    format!("warning: {speeds} (vx vy vz {x:.3} {y:.3} {z:.3}, wx wy wz {a:.3} {b:.3} {c:.3})")
}

/// `armgate jog`: a TW or jW stream for `seconds`, then wait until the arm has ramped to rest.
pub(super) fn jog(
    args: &JogArgs,
    cli: &Cli,
    client: &mut Client,
    out: &mut impl Write,
) -> Result<(), CliError> {
    let JogArgs {
        values,
        seconds,
        tool,
        rates,
    } = args;
    let (values, seconds, tool, rates) = (values.as_slice(), *seconds, *tool, *rates);
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
        Ok(streamed) => {
            if let Some(cut) = streamed.cut_to {
                writeln!(out, "{}", cut_warning(values, cut))?;
            }
            writeln!(
                out,
                "streamed {} commands over {:.2} s; the arm ramps to rest",
                streamed.sent,
                started.elapsed().as_secs_f64()
            )?;
        }
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
