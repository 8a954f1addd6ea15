//! `armgate run`: a via-point sequence from a TOML file, and the wait through its points.

use std::io::Write;
use std::path::PathBuf;

use clap::Args;

use super::options::WaitArgs;
use super::output::{fmt_values, follow, joint_progress, pose_progress, start};
use super::{Cli, CliError, joint_count};
use crate::{Client, RunFile};

/// `armgate run --help`: the run file's format.
pub(super) const RUN_LONG: &str = "\
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

/// `armgate run` arguments.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// The run file.
    pub file: PathBuf,
    /// Blend tolerance, mm (joints: mrad), for every point without its own `blend`: the
    /// sequence passes through them within it without stopping (VT/jT).
    #[arg(long)]
    pub blend: Option<f64>,
    /// Waiting.
    #[command(flatten)]
    pub wait: WaitArgs,
}

/// Loads the file, starts the sequence and waits until its last point is reached.
pub(super) fn run(
    args: &RunArgs,
    cli: &Cli,
    client: &mut Client,
    out: &mut impl Write,
) -> Result<(), CliError> {
    let RunArgs { file, blend, wait } = args;
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

#[cfg(test)]
mod tests {
    use super::super::testing::{cartesian_controller, run_with};
    use crate::fake::FakeController;
    use armgate_protocol::client::Command;

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
