//! A scripted calibration run (issue 37): `armgate calibrate measure` moves ur5, and ranger-mk1,
//! in armgate-sim through a plan's poses, its hook takes each reading from a perturbed "true"
//! arm (`simulate --perturb 7` on the reported joints), and the fit of what it wrote is
//! accepted (exit 0: better than nominal, residual within 3 × the noise, else it refuses) and
//! finds the perturbation (fitting poses' rms error below 0.2 mm, from 20 times that nominal).
//! With the whole arm's check (issue 35) most straight joint moves between the plan's poses
//! are refused: `measure` goes to the nearest pose the controller accepts, by whole turns of a
//! joint where that is shorter, and back the way it came when none is.
//!
//! armgate-sim is `$ARMGATE_SIM`, else `armgate-sim` next to this package's binary (built with
//! cargo if missing), as python/tests/conftest.py finds it.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

const CALIBRATE: &str = env!("CARGO_BIN_EXE_armgate-calibrate");

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn sim_binary() -> PathBuf {
    if let Some(given) = std::env::var_os("ARMGATE_SIM") {
        return given.into();
    }
    let sim = Path::new(CALIBRATE).with_file_name("armgate-sim");
    if !sim.is_file() {
        let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
        let built = Command::new(cargo)
            .args(["build", "-q", "-p", "armgate-sim"])
            .current_dir(repo())
            .status()
            .unwrap();
        assert!(built.success());
    }
    sim
}

/// armgate-sim on a free port; ended when dropped.
struct Sim(Child, String);

impl Drop for Sim {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn start_sim(robot: &str) -> Sim {
    let mut child = Command::new(sim_binary())
        .args(["--robot", robot, "--listen", "127.0.0.1:0", "--can", "off"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stderr = BufReader::new(child.stderr.take().unwrap());
    let mut addr = None;
    for line in stderr.lines() {
        let line = line.unwrap();
        if let Some(at) = line.find("udp://") {
            let rest = &line[at + 6..];
            addr = Some(rest.split([',', ' ']).next().unwrap().to_owned());
            break;
        }
    }
    Sim(child, addr.expect("armgate-sim's address"))
}

fn calibrate(args: &[&str], dir: &Path) -> std::process::Output {
    Command::new(CALIBRATE)
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap()
}

#[test]
fn a_measuring_run_on_ur5_in_the_simulator_is_fitted() {
    let robot = fast_joints("ur5");
    measure_and_fit("ur5", robot.to_str().unwrap(), 14, 14);
}

#[test]
fn a_measuring_run_on_ranger_mk1_in_the_simulator_is_fitted() {
    let robot = fast_joints("ranger-mk1");
    measure_and_fit("ranger-mk1", robot.to_str().unwrap(), 16, 16);
}

/// `robot`'s file with its joints (and drives) as fast as 3 rad/s at 6 rad/s², written to a
/// folder of its own: its kinematics, and so the fit, are the robot's; the moves between plan
/// poses take a second instead of several (ranger-mk1's 0.07–0.1 rad/s took minutes).
fn fast_joints(robot: &str) -> PathBuf {
    let dir = scratch(&format!("{robot}-file"));
    let text = std::fs::read_to_string(repo().join(format!("robots/{robot}.toml"))).unwrap();
    let mut fast = String::new();
    for line in text.lines() {
        let key = line.split('=').next().unwrap_or("").trim();
        let joint_line = !line.contains('[');
        let edited = match key {
            "max_velocity" if joint_line => "max_velocity = 3.0".to_owned(),
            "max_rate" => "max_rate = 3.1".to_owned(),
            "max_acceleration" if joint_line => "max_acceleration = 6.0".to_owned(),
            "drive" if !line.contains("max_speed") => {
                line.replace("drive = { ", "drive = { max_speed = 3.1, ")
            }
            _ => line.to_owned(),
        };
        fast.push_str(&edited);
        fast.push('\n');
    }
    let file = dir.join(format!("{robot}.toml"));
    std::fs::write(&file, fast).unwrap();
    file
}

/// A folder of its own under the temporary one.
fn scratch(what: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("armgate-measure-{what}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Plans `poses` poses for `robot`, measures them with `armgate calibrate measure` in
/// armgate-sim (at least `at_least` reached; no move the controller accepted is stopped on the
/// way, `motion aborted`: its check of the whole way and its tick's check agree), the hook reading a perturbed copy of the robot
/// (`simulate --perturb 7`), and fits the file it wrote: accepted, and the fit finds the
/// perturbation (the calibrated file reproduces the perturbed arm's positions far better than
/// the nominal one, as docs/calibration.md's simulated example).
fn measure_and_fit(name: &str, robot: &str, poses: usize, at_least: usize) {
    let dir = scratch(name);
    let count = poses.to_string();
    let plan = calibrate(
        &[
            "plan", "--robot", robot, "--poses", &count, "--out", "plan.csv",
        ],
        &dir,
    );
    assert!(plan.status.success(), "{plan:?}");
    let sim = start_sim(robot);
    // The instrument: the perturbed truth's tool position at the reported joints.
    let hook = format!(
        "echo \"$ARMGATE_JOINTS\" > p$ARMGATE_POSE.csv && {CALIBRATE} simulate --truth {robot} \
         --perturb 7 --seed $ARMGATE_POSE --poses p$ARMGATE_POSE.csv --out m$ARMGATE_POSE.csv \
         2>/dev/null && tail -1 m$ARMGATE_POSE.csv | cut -d, -f7-9"
    );
    let run = calibrate(
        &[
            "measure",
            "--robot",
            robot,
            "--plan",
            "plan.csv",
            "--out",
            "measured.csv",
            "--addr",
            &sim.1,
            "--hook",
            &hook,
        ],
        &dir,
    );
    let said = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{said}");
    assert!(!said.contains("motion aborted"), "{said}");
    drop(sim);
    // Every pose not skipped was reached and read: one line per "measured".
    let measured = std::fs::read_to_string(dir.join("measured.csv")).unwrap();
    let rows = measured
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with('q'))
        .count();
    assert_eq!(rows, said.matches(": measured").count(), "{said}");
    let skipped = said.matches(": skipped").count();
    assert_eq!(rows + skipped, poses, "{said}");
    assert!(rows >= at_least, "{name}: {said}");
    assert_eq!(
        measured.matches("# plan pose").count(),
        poses,
        "every plan pose is named: {measured}"
    );
    // The fit accepts it.
    let fit = calibrate(
        &[
            "--robot",
            robot,
            "--measurements",
            "measured.csv",
            "--noise-mm",
            "0.05",
            "--out",
            "calibrated.toml",
            "--instrument-out",
            "tracker.toml",
        ],
        &dir,
    );
    let report =
        String::from_utf8_lossy(&fit.stdout).into_owned() + &String::from_utf8_lossy(&fit.stderr);
    assert!(fit.status.success(), "{report}");
    assert!(dir.join("calibrated.toml").is_file());
    // The perturbation found: the fitting poses' rms error, nominal then calibrated.
    let rms = |row: &str| -> f64 {
        let line = report.lines().find(|l| l.starts_with(row)).expect(row);
        line.split_whitespace().nth(5).unwrap().parse().unwrap()
    };
    let (nominal, calibrated) = (
        rms("fitting poses, nominal"),
        rms("fitting poses, calibrated"),
    );
    eprintln!("{name}: rms {nominal} mm nominal, {calibrated} mm calibrated\n{report}");
    assert!(calibrated < 0.2, "{name}: {report}");
    assert!(nominal > 20.0 * calibrated, "{name}: {report}");
    let _ = std::fs::remove_dir_all(&dir);
}
