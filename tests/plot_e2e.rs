//! End to end: `armgate-sim --log-dir` logs a short session (a joint move, then Cartesian
//! mode), and `armgate plot` turns the logs into figures holding that session.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Command, Stdio};

use armgate_client::plot::{self, PlotArgs};
use armgate_client::{Client, Mode};
use armgate_plot::inspect::SvgSummary;

#[test]
fn a_logged_session_plots_with_its_moves_and_mode_changes() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let dir = std::env::temp_dir().join(format!("armgate-plot-e2e-{}", std::process::id()));
    let logs = dir.join("logs");
    let mut sim = Command::new(env!("CARGO_BIN_EXE_armgate-sim"))
        .args(["--listen", "127.0.0.1:0", "--quiet", "--duration", "4"])
        .arg("--robot")
        .arg(root.join("robots/ranger-mk1.toml"))
        .arg("--log-dir")
        .arg(&logs)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Kept open to the end: the simulator reports on stderr when it stops.
    let mut stderr = BufReader::new(sim.stderr.take().unwrap());
    let mut line = String::new();
    stderr.read_line(&mut line).unwrap();
    let addr = line
        .split("udp://")
        .nth(1)
        .and_then(|s| s.split(',').next())
        .unwrap_or_else(|| panic!("no address in {line:?}"))
        .trim()
        .to_owned();

    let mut arm = Client::connect(addr.as_str()).unwrap();
    // A few ticks in mode off first: the cycle handles a request in the tick it arrives for,
    // so a CM sent before the first tick would leave no "off" row in the log.
    std::thread::sleep(std::time::Duration::from_millis(200));
    arm.set_mode(Mode::Joint).unwrap();
    let mut q = arm.joints(6).unwrap();
    q[0] += 0.1;
    arm.joint_goal(&q).unwrap();
    // Refused (ER20) while the simulated drives are still starting.
    let started = std::time::Instant::now();
    while let Err(e) = arm.joint_begin() {
        assert!(started.elapsed().as_secs() < 2, "jB never accepted: {e}");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    std::thread::sleep(std::time::Duration::from_millis(1500));
    arm.set_mode(Mode::Cartesian).unwrap();
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut stderr, &mut rest).unwrap();
    assert!(sim.wait().unwrap().success(), "{rest}");

    let mut listing = Vec::new();
    let written = plot::run(
        &PlotArgs {
            dir: logs.clone(),
            out: Some(dir.join("plots")),
        },
        &mut listing,
    )
    .unwrap();
    assert_eq!(written.len(), 2);
    let read = |name: &str| {
        SvgSummary::parse(&std::fs::read_to_string(dir.join("plots").join(name)).unwrap()).unwrap()
    };
    let joints = read("joints.svg");
    // The modes in order, on each of the six panels.
    for mode in ["off", "joint", "cartesian"] {
        let n = joints.texts.iter().filter(|t| t.trim() == mode).count();
        assert_eq!(n, 6, "{mode}: {:?}", joints.texts);
    }
    // Measured and commanded, per joint, each a line of many points (4 s of ticks).
    assert!(joints.lines_with_points(30) >= 12, "{:?}", joints.polylines);
    let path = read("tool-path.svg");
    assert!(path.has_text("top view, x–y") && path.has_text("position (m)"));
    assert!(path.lines_with_points(30) >= 3, "{:?}", path.polylines);
    std::fs::remove_dir_all(&dir).unwrap();
}
