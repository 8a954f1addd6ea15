//! The inverse-kinematics subcommands: `ik` (every solution of a pose) and `ik-move`.

use std::io::Write;

use armgate_protocol::client::branch::NAMES;

use clap::Args;

use super::CliError;
use super::options::{PoseArgs, WaitArgs, parse_seconds};
use super::output::{fmt_values, follow, joint_progress, start};
use crate::{Client, IkSolution, Redundancy};

/// `armgate ik` arguments.
#[derive(Debug, Args)]
pub struct IkArgs {
    /// The pose.
    #[command(flatten)]
    pub pose: PoseArgs,
    /// The redundancy values.
    #[command(flatten)]
    pub redundancy: RedundancyArgs,
}

/// The redundancy parameters of a 7–8 joint arm (docs/kinematics.md, "Redundant arms"); a
/// value not given keeps the present one.
#[derive(Debug, Args)]
pub struct RedundancyArgs {
    /// θ3 (rad) on a 7–8 joint arm (iiwa14, ranger-mk2): the solutions that put joint 3 at this
    /// value instead of its present one (sent first with KR).
    #[arg(long, value_name = "RAD", allow_negative_numbers = true)]
    pub theta3: Option<f64>,
    /// θ5 (rad) on an 8-joint arm (ranger-mk2): likewise for joint 5.
    #[arg(long, value_name = "RAD", allow_negative_numbers = true)]
    pub theta5: Option<f64>,
}

impl RedundancyArgs {
    /// The `KR` choice, if a value was given.
    fn choice(&self) -> Option<Redundancy> {
        let Self { theta3, theta5 } = *self;
        (theta3.is_some() || theta5.is_some()).then(|| Redundancy {
            theta3: theta3.map(|v| v as f32),
            theta5: theta5.map(|v| v as f32),
        })
    }
}

/// `armgate ik-move` arguments.
#[derive(Debug, Args)]
pub struct IkMoveArgs {
    /// The pose.
    #[command(flatten)]
    pub pose: PoseArgs,
    /// The configuration: `shoulder-left,elbow-up,wrist-noflip` (each of the three, any
    /// order), its short form `lun` (l/r, u/d, n/f), or its number 0..=7 (1 shoulder right,
    /// 2 elbow down, 4 wrist flip), as `armgate ik` prints them; without it, the solution
    /// nearest the present joints.
    #[arg(long, value_parser = parse_branch)]
    pub branch: Option<u8>,
    /// The redundancy values (no solution for them: refused, no others are tried).
    #[command(flatten)]
    pub redundancy: RedundancyArgs,
    /// Minimum duration (`5`, `5s`, `1500ms`; bare: seconds).
    #[arg(long, default_value_t = 0.0, value_parser = parse_seconds)]
    pub time: f64,
    /// Waiting.
    #[command(flatten)]
    pub wait: WaitArgs,
}

/// `armgate ik`: KS, every solution with its branch (and its joints 7.. on an arm of more than
/// six `joints`), for the present or the chosen redundancy values.
pub(super) fn ik(
    args: &IkArgs,
    joints: usize,
    client: &mut Client,
    out: &mut impl Write,
) -> Result<(), CliError> {
    let IkArgs { pose, redundancy } = args;
    let (xyz, rpy) = pose.xyz_rpy();
    let Some(solutions) = client.ik_solutions(xyz, rpy, joints, redundancy.choice())? else {
        writeln!(out, "no closed-form IK for this robot (docs/kinematics.md)")?;
        return Ok(());
    };
    writeln!(
        out,
        "{} solutions{} (branch: number = 1 shoulder right + 2 elbow down + 4 wrist flip)",
        solutions.len(),
        redundancy_values(&solutions, joints, redundancy)
    )?;
    // The arm's own branch, and the solution nearest its joints: what ik-move without
    // --branch moves to (best effort: a controller without the reports marks none).
    let present = client.present_branch().ok().flatten();
    let here = client.joints(joints).ok();
    let nearest = here.as_ref().and_then(|q| {
        solutions
            .iter()
            .map(|s| (s.branch, distance(&s.q, q)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(branch, _)| branch)
    });
    for s in &solutions {
        let mut marks = Vec::new();
        if present == Some(s.branch) {
            marks.push("the arm's present branch");
        }
        if nearest == Some(s.branch) {
            marks.push("nearest the joints: ik-move's choice without --branch");
        }
        let marks = if marks.is_empty() {
            String::new()
        } else {
            format!("   <- {}", marks.join("; "))
        };
        writeln!(
            out,
            "  branch {} {:<40} {}{marks}",
            s.branch,
            branch_name(s.branch),
            fmt_values(&s.q, 6)
        )?;
    }
    if solutions.is_empty() {
        return Err(CliError::NoSolution(
            "no IK solution of this pose within the joint limits".to_owned(),
        ));
    }
    Ok(())
}

/// The names of branch `bits`: `shoulder-left,elbow-up,wrist-noflip (lun)`.
pub(super) fn branch_name(bits: u8) -> String {
    let named = NAMES.map(|(bit, [clear, set])| if bits & bit != 0 { set } else { clear });
    let short: String = named.iter().map(|(_, c)| c).collect();
    let long: Vec<&str> = named.iter().map(|(n, _)| *n).collect();
    format!("{} ({short})", long.join(","))
}

/// `--branch`: the three names (any order), their short form, or the bits 0..=7.
fn parse_branch(s: &str) -> Result<u8, String> {
    let refused = || {
        format!(
            "`{s}`: a branch is its three names, e.g. `shoulder-left,elbow-up,wrist-noflip`, \
             short `lun` (shoulder l/r, elbow u/d, wrist n/f), or its number 0 to 7 (1 \
             shoulder right + 2 elbow down + 4 wrist flip); `armgate ik` lists those with a \
             solution; leave --branch out for the solution nearest the present joints"
        )
    };
    if let Ok(bits) = s.parse::<u8>() {
        return if bits <= 7 { Ok(bits) } else { Err(refused()) };
    }
    let words: Vec<String> = if s.contains(',') {
        s.split(',').map(|w| w.trim().to_owned()).collect()
    } else {
        // The short form: one letter each.
        s.chars().map(String::from).collect()
    };
    let mut bits = 0;
    for (bit, states) in NAMES {
        let found = states
            .iter()
            .position(|(name, short)| words.iter().any(|w| *w == *name || w.chars().eq([*short])));
        match found {
            Some(set) => bits |= if set == 1 { bit } else { 0 },
            None => return Err(refused()),
        }
    }
    if words.len() == NAMES.len() {
        Ok(bits)
    } else {
        Err(refused())
    }
}

/// How far apart two joint vectors are as the controller measures it when it picks the
/// solution nearest the present joints (`KG` without a branch): `1 − cos Δ` summed over their
/// common joints (a slide, in metres, counts `Δ²/2` there: the same to second order).
fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| 1.0 - (x - y).cos()).sum()
}

/// On a 7–8 joint arm, the redundancy values the solutions share, which name each solution
/// together with its branch: ` for θ3 = 0.300 (present)`, `… (chosen)`; empty otherwise.
fn redundancy_values(solutions: &[IkSolution], joints: usize, args: &RedundancyArgs) -> String {
    let Some(first) = solutions.first().filter(|_| joints > 6) else {
        return String::new();
    };
    let parameters: &[(usize, &str, Option<f64>)] =
        &[(2, "θ3", args.theta3), (4, "θ5", args.theta5)];
    let named: Vec<String> = parameters
        .iter()
        .take(if joints > 7 { 2 } else { 1 })
        .filter_map(|(i, name, chosen)| {
            let how = if chosen.is_some() {
                "chosen"
            } else {
                "present"
            };
            first.q.get(*i).map(|v| format!("{name} = {v:.3} ({how})"))
        })
        .collect();
    format!(" for {}", named.join(", "))
}

/// `armgate ik-move`: KG, then wait until the joints are there.
pub(super) fn ik_move(
    args: &IkMoveArgs,
    client: &mut Client,
    out: &mut impl Write,
) -> Result<(), CliError> {
    let IkMoveArgs {
        pose,
        branch,
        redundancy,
        time,
        wait,
    } = args;
    let (xyz, rpy) = pose.xyz_rpy();
    let interrupt = wait.interrupt();
    let choice = redundancy.choice();
    let goal = start(client, |c| c.ik_move(xyz, rpy, (*branch, choice), *time))?;
    writeln!(
        out,
        "moving to {} (branch {} {})",
        fmt_values(&goal.q, 4),
        goal.branch,
        branch_name(goal.branch)
    )?;
    if wait.no_wait {
        return Ok(());
    }
    let options = wait.options(*time, None, interrupt.as_ref());
    let reached = follow(client, |c| {
        c.wait_until_joints(&goal.q, &options, joint_progress)
    })?;
    writeln!(out, "arrived: {}", fmt_values(&reached, 4))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::testing::{cartesian_controller, run_with};
    use armgate_protocol::client::Command;

    #[test]
    fn a_pose_without_a_solution_exits_5() {
        // KS answered with no solution (f6 = 0) on a robot with a closed form.
        let fake = cartesian_controller(|_, _| {});
        let (result, out) = run_with(&fake, &["ik", "0", "0.2", "9", "0", "0", "0"]);
        let err = result.unwrap_err();
        assert_eq!(err.exit_code(), crate::exit::NO_SOLUTION, "{err}");
        assert!(out.starts_with("0 solutions"), "{out}");
        assert_eq!(
            err.to_string(),
            "no IK solution of this pose within the joint limits"
        );
        // --branch 8 says what a branch is.
        let cli = <crate::cli::Cli as clap::Parser>::try_parse_from([
            "armgate", "ik-move", "0", "0", "0", "0", "0", "0", "--branch", "8",
        ]);
        let message = cli.unwrap_err().to_string();
        assert!(
            message.contains("a branch is its three names, e.g. `shoulder-left,elbow-up"),
            "{message}"
        );
        assert!(message.contains("number 0 to 7"), "{message}");
        // Two solutions: success.
        let fake = cartesian_controller(|r, reply| {
            if r.command == Command::IkSolution {
                reply.values[6] = 2.0;
            }
        });
        let (result, out) = run_with(&fake, &["ik", "0", "0.2", "0.8", "0", "0", "0"]);
        result.unwrap();
        assert!(out.starts_with("2 solutions"), "{out}");
    }

    #[test]
    fn branches_are_read_by_name_short_form_or_number() {
        use super::{branch_name, parse_branch};
        assert_eq!(parse_branch("shoulder-left,elbow-up,wrist-noflip"), Ok(0));
        assert_eq!(parse_branch("wrist-flip, shoulder-right,elbow-up"), Ok(5));
        assert_eq!(parse_branch("rdf"), Ok(7));
        assert_eq!(parse_branch("lun"), Ok(0));
        assert_eq!(parse_branch("ldn"), Ok(2));
        assert_eq!(parse_branch("6"), Ok(6));
        for bad in [
            "8",
            "lu",
            "lunn",
            "shoulder-left,elbow-up",
            "xyz",
            "rr n",
            "l,u,n,f",
        ] {
            assert!(parse_branch(bad).is_err(), "{bad}");
        }
        assert_eq!(branch_name(0), "shoulder-left,elbow-up,wrist-noflip (lun)");
        assert_eq!(branch_name(6), "shoulder-left,elbow-down,wrist-flip (ldf)");
        for bits in 0..8 {
            let name = branch_name(bits);
            let (long, short) = name.split_once(' ').unwrap();
            assert_eq!(parse_branch(long), Ok(bits));
            assert_eq!(parse_branch(short.trim_matches(['(', ')'])), Ok(bits));
        }
    }
}
