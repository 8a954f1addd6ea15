//! `armgate calibrate measure`: the measuring run. It moves the arm through a plan's joint
//! configurations (`plan --out plan.csv`) with `jG` + `jB`, waits for each motion to end and
//! the arm to settle, reads the joints the controller reports (`jP`), takes the instrument's
//! reading, and writes the file the fit reads (`q1..qn,x,y,z,weight`, each line after a comment
//! naming its plan pose).
//!
//! The controller checks every joint move's straight way for the whole arm (a link through
//! the base, the tool past the bounds: docs/safety.md), and the straight way between two
//! calibration poses often fails it. So the run does not go through the plan in order: from
//! where the arm is it goes to the nearest pose not yet measured whose way the controller
//! accepts (a refused `jB` moves nothing); when it accepts none, the arm goes back the way it
//! came (each way back is one the controller accepted forwards), one pose at a time down to
//! the pose the run began from, and tries again from there. A pose refused from every pose
//! the arm was at (its goal itself in collision, say), or a motion the controller stops, is
//! skipped with its reason (said on stderr and as a comment in the file).
//!
//! The instrument's side is one of: a prompt (type `x,y,z` in metres, an empty line skips the
//! pose), a hook (`--hook CMD`, run by `sh -c` at each pose with `ARMGATE_POSE` (1-based) and
//! `ARMGATE_JOINTS` (the reported joints, comma-separated) in its environment; the last line of
//! its output is `x,y,z`; a failure skips the pose), so that a tracker's own software takes the
//! reading, or none (`--joints-only`: the reported joints, in the plan's format, to pair with
//! the instrument's file later).

use std::io::{BufRead, Write};
use std::path::PathBuf;
use std::time::Duration;

use armgate_calibrate::fit::Measurement;
use armgate_calibrate::measurements;
use armgate_client::cli::parse_duration;
use armgate_client::{Client, ClientConfig, ClientError, Mode, Signer, WaitOptions};
use armgate_core::config::{JointConfig, JointType, RobotConfig};
use clap::Args;
use nalgebra::Vector3;

/// `measure`'s options.
#[derive(Debug, Args)]
pub struct MeasureArgs {
    /// The robot file (its joint count reads the plan).
    #[arg(long)]
    pub robot: PathBuf,
    /// The joint configurations to visit (CSV, as `plan` writes them), nearest first.
    #[arg(long)]
    pub plan: PathBuf,
    /// Where to write the measurements (the fit's `--measurements`).
    #[arg(long)]
    pub out: PathBuf,
    /// The controller's address, host:port.
    #[arg(long, env = "ARMGATE_ADDR", default_value = armgate_client::DEFAULT_ADDR)]
    pub addr: String,
    /// Sign the requests with the key in this file (a controller with a key).
    #[arg(long, env = "ARMGATE_KEY_FILE", value_name = "FILE")]
    pub key: Option<PathBuf>,
    /// With --key: the link id to sign with, 1..=255 (default: a free one the controller sets
    /// aside).
    #[arg(long, env = "ARMGATE_LINK_ID")]
    pub link_id: Option<u8>,
    /// With --key: the controller's id, 8 hex digits (default: the one it names).
    #[arg(long, env = "ARMGATE_CONTROLLER_ID", value_name = "HEX")]
    pub controller_id: Option<armgate_protocol::client::signed::ControllerId>,
    /// The instrument's reading by a command run at each pose (see above); without it and
    /// without --joints-only, a prompt.
    #[arg(long, value_name = "CMD", conflicts_with = "joints_only")]
    pub hook: Option<String>,
    /// No instrument: write the reported joints only (the plan's format).
    #[arg(long)]
    pub joints_only: bool,
    /// How long to let the arm settle after each motion before reading (`500ms`, `1s`).
    #[arg(long, default_value = "500ms", value_parser = parse_duration)]
    pub settle: Duration,
}

/// Why a pose was not measured.
enum Refusal {
    /// The controller refused the motion from where the arm is.
    Refused(String),
    /// The motion did not arrive.
    NotReached(String),
}

/// The joints reported at a visited pose, or why it was not measured.
type Visit = Result<Vec<f64>, Refusal>;

/// Runs the measuring run; returns an error only when the controller cannot be talked to or
/// a file cannot be read or written (a pose that fails is skipped).
pub fn run(args: &MeasureArgs, config: &RobotConfig) -> Result<(), String> {
    let dof = config.dof();
    let text =
        std::fs::read_to_string(&args.plan).map_err(|e| format!("{}: {e}", args.plan.display()))?;
    let plan = measurements::parse_poses(&text, dof)
        .map_err(|e| format!("{}: {e}", args.plan.display()))?;
    let mut client = Client::connect_with(args.addr.as_str(), ClientConfig::default())
        .map_err(|e| e.to_string())?;
    if let Some(key) = &args.key {
        let mut signer = Signer::from_file(key, args.link_id).map_err(|e| e.to_string())?;
        if let Some(id) = args.controller_id {
            signer.set_controller(id);
        }
        client.set_signer(Some(signer));
    }
    client
        .set_mode(Mode::Joint)
        .map_err(|e| format!("CM 1: {e}"))?;
    let start = client.joints(dof).map_err(|e| format!("jP: {e}"))?;
    let mut out = String::new();
    let (mut measured, mut skipped) = (0usize, 0usize);
    let mut record =
        |k: usize, reading: Result<(Vec<f64>, Option<Vector3<f64>>), String>| match reading {
            Ok((q, position)) => {
                eprintln!("pose {}/{}: measured", k + 1, plan.len());
                out += &format!("# plan pose {}\n", k + 1);
                out += &row(q, position, dof);
                measured += 1;
            }
            Err(why) => {
                eprintln!("pose {}/{}: skipped: {why}", k + 1, plan.len());
                out += &format!("# plan pose {} skipped: {why}\n", k + 1);
                skipped += 1;
            }
        };
    // The poses the arm went through, each reached from the one before: the way back.
    let mut trail = vec![start];
    let mut pending: Vec<usize> = (0..plan.len()).collect();
    // Each plan pose's first refusal, its reason if it is never reached.
    let mut refused: Vec<Option<String>> = vec![None; plan.len()];
    // Whether the arm could not go back the way it came (the poses left were not all tried).
    let mut stranded = false;
    // Each round measures or skips a pose or steps back one pose: bounded.
    while !pending.is_empty() {
        let Some(here) = trail.last().cloned() else {
            break;
        };
        let away = |k: usize| plan.get(k).map_or(f64::INFINITY, |g| distance(&here, g));
        pending.sort_by(|&a, &b| away(a).total_cmp(&away(b)));
        let mut went = None;
        'poses: for (i, &k) in pending.iter().enumerate() {
            let Some(want) = plan.get(k) else { continue };
            let near = nearest_turn(&here, want, &config.joints);
            let goals = if near == *want {
                vec![near]
            } else {
                vec![near, want.clone()]
            };
            for goal in goals {
                match visit(&mut client, &goal, args.settle)? {
                    Err(Refusal::Refused(why)) => {
                        if let Some(first) = refused.get_mut(k) {
                            first.get_or_insert(why);
                        }
                    }
                    done => {
                        went = Some((i, k, goal, done));
                        break 'poses;
                    }
                }
            }
        }
        match went {
            Some((i, k, goal, Ok(q))) => {
                pending.remove(i);
                record(k, read_instrument(args, k, &q).map(|p| (q, p)));
                trail.push(goal);
            }
            Some((i, k, _, Err(Refusal::Refused(why) | Refusal::NotReached(why)))) => {
                pending.remove(i);
                record(k, Err(why));
                // The arm stopped somewhere on a way accepted from here: back here.
                if !step_back(&mut client, &here, args.settle)? {
                    stranded = true;
                    break;
                }
            }
            None => {
                // No pose left is accepted from here: back the way the arm came.
                trail.pop();
                match trail.last() {
                    Some(back) if step_back(&mut client, back, args.settle)? => {}
                    Some(_) => {
                        stranded = true;
                        break;
                    }
                    None => break,
                }
            }
        }
    }
    for k in pending {
        let why = match refused.get(k).cloned().flatten() {
            Some(why) if !stranded => format!("{why} (from every pose the arm was at)"),
            Some(why) => format!("{why} (the arm could not go back to try it from elsewhere)"),
            None => "not tried: the arm could not go back the way it came".into(),
        };
        record(k, Err(why));
    }
    let header = if args.joints_only {
        measurements::format_poses(&[], dof)
    } else {
        measurements::format(&[], dof)
    };
    std::fs::write(&args.out, header + &out).map_err(|e| format!("{}: {e}", args.out.display()))?;
    eprintln!(
        "wrote {measured} of {} plan poses to {} ({skipped} skipped)",
        plan.len(),
        args.out.display()
    );
    if measured == 0 {
        return Err("no pose was measured".into());
    }
    Ok(())
}

/// The joint-space distance between two configurations (the nearest pose next).
fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(a, b)| (a - b) * (a - b)).sum()
}

/// `goal` with each revolute joint turned by whole turns to the angle nearest `here` within
/// its limits: the same arm shape and tool pose (the fit reads the reported joints), by a
/// shorter way (a plan's joints span ±2π; 6 rad of elbow folds the forearm through the base).
fn nearest_turn(here: &[f64], goal: &[f64], joints: &[JointConfig]) -> Vec<f64> {
    let turn = std::f64::consts::TAU;
    goal.iter()
        .zip(here)
        .zip(joints)
        .map(|((&g, &h), j)| {
            if j.kind != JointType::Revolute {
                return g;
            }
            // Limits span at most a few turns: -2..=2 whole turns cover ±4π.
            (-2..=2)
                .map(|n| g + f64::from(n) * turn)
                .filter(|v| (j.min..=j.max).contains(v))
                .min_by(|a, b| (a - h).abs().total_cmp(&(b - h).abs()))
                .unwrap_or(g)
        })
        .collect()
}

/// One line of the measurements file: the reported joints and the reading, or the joints only.
fn row(q: Vec<f64>, position: Option<Vector3<f64>>, dof: usize) -> String {
    let text = match position {
        Some(position) => measurements::format(
            &[Measurement {
                q,
                position,
                weight: 1.0,
                line: 0,
            }],
            dof,
        ),
        None => measurements::format_poses(&[q], dof),
    };
    // The row without the header.
    text.lines().nth(1).unwrap_or_default().to_owned() + "\n"
}

/// Moves back to `pose` (the reverse of a way the controller accepted); `false`, said on
/// stderr, if it refuses or the arm does not get there (the run ends there).
fn step_back(client: &mut Client, pose: &[f64], settle: Duration) -> Result<bool, String> {
    match visit(client, pose, settle)? {
        Ok(_) => Ok(true),
        Err(Refusal::Refused(why) | Refusal::NotReached(why)) => {
            eprintln!("going back the way the arm came: {why}; the run ends here");
            Ok(false)
        }
    }
}

/// Moves to `goal` and reads the joints once the arm has settled; a refusal or a motion that
/// did not arrive is the pose's reason to be skipped, no reply ends the run.
fn visit(client: &mut Client, goal: &[f64], settle: Duration) -> Result<Visit, String> {
    let started = client.joint_goal(goal).and_then(|_| client.joint_begin());
    let planned = match started {
        Ok(planned) => planned,
        Err(ClientError::Rejected(text)) => {
            return Ok(Err(Refusal::Refused(format!("refused: {text}"))));
        }
        Err(e) => return Err(e.to_string()),
    };
    // Twice the planned duration and a margin, as `armgate jmove` waits.
    let defaults = WaitOptions::default();
    let options = WaitOptions {
        timeout: planned.map_or(defaults.timeout, |p| {
            p.saturating_mul(2).saturating_add(Duration::from_secs(30))
        }),
        ..defaults
    };
    if let Err(e) = client.wait_until_joints(goal, &options, |_| {}) {
        // A stopped motion brakes first: the next move would be refused as busy.
        client
            .wait_motion_ended(Duration::from_secs(5))
            .map_err(|e| e.to_string())?;
        return Ok(Err(Refusal::NotReached(e.to_string())));
    }
    client
        .wait_motion_ended(Duration::from_secs(5))
        .map_err(|e| e.to_string())?;
    std::thread::sleep(settle);
    client.joints(goal.len()).map(Ok).map_err(|e| e.to_string())
}

/// The instrument's reading at plan pose `k` (0-based) with the reported joints `q`: none for
/// `--joints-only`, else the hook's or the prompt's `x,y,z`.
fn read_instrument(
    args: &MeasureArgs,
    k: usize,
    q: &[f64],
) -> Result<Option<Vector3<f64>>, String> {
    if args.joints_only {
        return Ok(None);
    }
    let joints: Vec<String> = q.iter().map(|v| format!("{v:.9}")).collect();
    let line = match &args.hook {
        Some(cmd) => {
            let output = std::process::Command::new("sh")
                .args(["-c", cmd])
                .env("ARMGATE_POSE", (k + 1).to_string())
                .env("ARMGATE_JOINTS", joints.join(","))
                .output()
                .map_err(|e| format!("hook: {e}"))?;
            if !output.status.success() {
                return Err(format!("hook exited with {}", output.status));
            }
            String::from_utf8_lossy(&output.stdout)
                .lines()
                .rfind(|l| !l.trim().is_empty())
                .unwrap_or_default()
                .to_owned()
        }
        None => {
            eprint!(
                "pose {}: the arm is at {}; measure the tool and type x,y,z (m), or Enter to \
                 skip: ",
                k + 1,
                joints.join(" ")
            );
            let _ = std::io::stderr().flush();
            let mut line = String::new();
            std::io::stdin()
                .lock()
                .read_line(&mut line)
                .map_err(|e| format!("prompt: {e}"))?;
            if line.trim().is_empty() {
                return Err("no reading given".into());
            }
            line
        }
    };
    position(&line).map(Some)
}

/// `x,y,z` (m).
fn position(line: &str) -> Result<Vector3<f64>, String> {
    let values: Result<Vec<f64>, _> = line.split(',').map(|v| v.trim().parse()).collect();
    match values.as_deref() {
        Ok([x, y, z]) if [x, y, z].iter().all(|v| v.is_finite()) => Ok(Vector3::new(*x, *y, *z)),
        _ => Err(format!("`{}` is not x,y,z in metres", line.trim())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_instrument_reading_is_three_finite_numbers() {
        assert_eq!(
            position(" 0.5, -0.25 ,1\n"),
            Ok(Vector3::new(0.5, -0.25, 1.0))
        );
        assert!(position("0.5,0.2").is_err());
        assert!(position("a,b,c").is_err());
        assert!(position("0.5,NaN,1").is_err());
    }
}
