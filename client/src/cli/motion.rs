//! The subcommands that move the arm to a goal and wait: `move` (a Cartesian pose) and
//! `jmove` (joint values).

use std::io::Write;

use clap::Args;

use super::options::{PoseArgs, WaitArgs, parse_seconds};
use super::output::{fmt_values, follow, joint_progress, pose_progress, start};
use super::{Cli, CliError, joint_count};
use crate::banks::MAX_JOINTS;
use crate::{Client, Pose};

/// `armgate move` arguments.
#[derive(Debug, Args)]
pub struct MoveArgs {
    /// The goal.
    #[command(flatten)]
    pub pose: PoseArgs,
    /// Minimum duration (`5`, `5s`, `1500ms`; bare: seconds); 0 = as fast as the controller's
    /// limits allow.
    #[arg(long, default_value_t = 0.0, value_parser = parse_seconds)]
    pub time: f64,
    /// Waiting.
    #[command(flatten)]
    pub wait: WaitArgs,
}

/// `armgate jmove` arguments.
#[derive(Debug, Args)]
pub struct JmoveArgs {
    /// One value per joint (rad, or m for prismatic joints), as many as the arm has.
    #[arg(required = true, num_args = 1..=MAX_JOINTS, allow_negative_numbers = true)]
    pub q: Vec<f64>,
    /// Minimum duration (`5`, `5s`, `1500ms`; bare: seconds).
    #[arg(long, value_parser = parse_seconds)]
    pub time: Option<f64>,
    /// Waiting.
    #[command(flatten)]
    pub wait: WaitArgs,
}

/// `armgate move`: GT + BG, then wait until the tool is at the goal.
pub(super) fn move_to(
    args: &MoveArgs,
    client: &mut Client,
    out: &mut impl Write,
) -> Result<(), CliError> {
    let MoveArgs { pose, time, wait } = args;
    let (xyz, rpy) = pose.xyz_rpy();
    let interrupt = wait.interrupt();
    client.goal_rpy(xyz, rpy, *time)?;
    let planned = start(client, Client::begin)?;
    writeln!(out, "moving")?;
    if wait.no_wait {
        return Ok(());
    }
    let goal = Pose::from_xyz_rpy(xyz, rpy);
    let options = wait.options(*time, planned, interrupt.as_ref());
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

/// `armgate jmove`: jG + jB, or with a time a one-point joint sequence; then wait.
pub(super) fn jmove(
    args: &JmoveArgs,
    cli: &Cli,
    client: &mut Client,
    out: &mut impl Write,
) -> Result<(), CliError> {
    let JmoveArgs { q, time, wait } = args;
    check_joint_count(q.len(), joint_count(cli, client)?)?;
    let interrupt = wait.interrupt();
    let planned = match time {
        None => {
            client.joint_goal(q)?;
            start(client, Client::joint_begin)?
        }
        Some(t) => {
            client.joint_via_clear()?;
            client.via_joint(0, q, *t)?;
            start(client, Client::run_joint_sequence)?;
            None
        }
    };
    writeln!(out, "moving")?;
    if wait.no_wait {
        return Ok(());
    }
    let options = wait.options(time.unwrap_or(0.0), planned, interrupt.as_ref());
    let reached = follow(client, |c| c.wait_until_joints(q, &options, joint_progress))?;
    writeln!(out, "arrived: {}", fmt_values(&reached, 4))?;
    Ok(())
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

#[cfg(test)]
mod tests {
    use super::super::CliError;
    use super::super::testing::{cartesian_controller, run_with};
    use crate::fake::{FakeController, echo, text};
    use crate::status::tests::status_reply;
    use armgate_protocol::client::Command;

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
}
