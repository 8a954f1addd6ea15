//! `armgate-calibrate` end to end: plan, simulate, calibrate through files, and its errors.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)] // helpers of tests: a panic is a failed test

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use armgate_calibrate::instrument::Placement;
use armgate_calibrate::measurements::parse;
use armgate_core::config::load_file;
use armgate_core::kinematics::Chain;
use nalgebra::Point3;

fn tool(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_armgate-calibrate"))
        .args(args)
        .output()
        .unwrap()
}

/// Runs the tool and requires it to succeed (else fails with its stderr).
fn tool_ok(args: &[&str]) -> Output {
    let run = tool(args);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    run
}

fn robot(name: &str) -> String {
    format!("{}/../robots/{name}.toml", env!("CARGO_MANIFEST_DIR"))
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("armgate-calibrate-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn plan_simulate_calibrate() {
    let dir = scratch("cli");
    let (plan, measured, out) = (
        dir.join("plan.csv"),
        dir.join("m.csv"),
        dir.join("out.toml"),
    );
    let ur5 = robot("ur5");
    tool_ok(&[
        "plan",
        "--robot",
        &ur5,
        "--poses",
        "40",
        "--candidates",
        "400",
        "--out",
        s(&plan),
    ]);
    tool_ok(&[
        "simulate",
        "--truth",
        &ur5,
        "--perturb",
        "3",
        "--poses",
        s(&plan),
        "--out",
        s(&measured),
    ]);
    let run = tool_ok(&[
        "--robot",
        &ur5,
        "--measurements",
        s(&measured),
        "--out",
        s(&out),
    ]);
    let report = String::from_utf8_lossy(&run.stdout);
    assert!(report.contains("5-fold cross-validation"), "{report}");
    assert!(
        report.contains("not identifiable (kept nominal): J1.theta"),
        "{report}"
    );
    // The written file loads and carries the report.
    load_file(&out).unwrap();
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.contains("# 5-fold cross-validation"));
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn bad_measurements_name_the_line_and_write_nothing() {
    let dir = scratch("bad");
    let (measured, out) = (dir.join("m.csv"), dir.join("out.toml"));
    let calibrate = || {
        tool(&[
            "--robot",
            &robot("ur5"),
            "--measurements",
            s(&measured),
            "--out",
            s(&out),
        ])
    };
    std::fs::write(
        &measured,
        "q1,q2,q3,q4,q5,q6,x,y,z\n0,0,0,0,0,0,1,2,3\n0,0,0,0,0,1,2\n",
    )
    .unwrap();
    let run = calibrate();
    assert_eq!(run.status.code(), Some(2));
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(err.contains("line 3"), "{err}");
    assert!(!out.exists());
    // Too few poses for the parameters: refused, not a wild fit.
    std::fs::write(&measured, "0,0,0,0,0,0,1,2,3\n").unwrap();
    let run = calibrate();
    assert_eq!(run.status.code(), Some(2));
    assert!(!out.exists());
    std::fs::remove_dir_all(dir).unwrap();
}

/// A tracker 1.9 m from the robot, turned 35° and tilted 1°, through files: the calibrated file
/// keeps the robot's frame and workspace, the instrument file predicts held-out measurements, a
/// gross error is set aside by line, a missing value is refused by line, a fit far above the
/// stated noise is refused unless forced, and `--world-base` puts the robot in the tracker's
/// frame with its workspace.
#[test]
fn a_tracker_through_files() {
    let dir = scratch("tracker");
    let at = |name: &str| dir.join(name);
    let mk1 = robot("ranger-mk1");
    std::fs::write(
        at("tracker.toml"),
        "[instrument]\nxyz = [1.2, -1.45, 0.3]\nrpy = [0.0122, -0.0105, 0.6109]\n",
    )
    .unwrap();
    for (poses, seed, out) in [("50", "1", "m.csv"), ("100", "2", "check.csv")] {
        let plan = at(&format!("plan-{seed}.csv"));
        tool_ok(&[
            "plan",
            "--robot",
            &mk1,
            "--poses",
            poses,
            "--seed",
            seed,
            "--candidates",
            "300",
            "--out",
            s(&plan),
        ]);
        tool_ok(&[
            "simulate",
            "--truth",
            &mk1,
            "--perturb",
            "7",
            "--instrument",
            s(&at("tracker.toml")),
            "--poses",
            s(&plan),
            "--seed",
            seed,
            "--out",
            s(&at(out)),
        ]);
    }
    let calibrate = |data: &str, extra: &[&str]| {
        let (check, out) = (at("check.csv"), at("out.toml"));
        let _ = std::fs::remove_file(&out);
        let mut args = vec!["--robot", &mk1, "--measurements", data];
        args.extend_from_slice(&["--held-out", s(&check), "--out", s(&out)]);
        args.extend_from_slice(extra);
        tool(&args)
    };
    let fitted = at("fitted.toml");
    let run = calibrate(
        s(&at("m.csv")),
        &["--noise-mm", "0.05", "--instrument-out", s(&fitted)],
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let nominal = load_file(&mk1).unwrap();
    let out = load_file(at("out.toml")).unwrap();
    assert_eq!(
        (out.base, &out.workspace),
        (nominal.base, &nominal.workspace)
    );
    // The held-out measurements, predicted by the two files.
    let placement = Placement::parse(&std::fs::read_to_string(&fitted).unwrap()).unwrap();
    assert!((placement.pose.translation.vector.norm() - 1.906).abs() < 0.02);
    let check = parse(&std::fs::read_to_string(at("check.csv")).unwrap(), 6).unwrap();
    let chain = Chain::new(&out);
    let mean = check
        .iter()
        .map(|m| {
            let world = Point3::from(chain.forward(&m.q).unwrap().translation.vector);
            (placement.pose.inverse() * world - Point3::from(m.position)).norm()
        })
        .sum::<f64>()
        / check.len() as f64;
    assert!(mean < 0.15e-3, "{mean}");

    // Line 19's x off by 0.5 m: set aside and named; the file is written.
    let text = std::fs::read_to_string(at("m.csv")).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut fields: Vec<String> = lines[18].split(',').map(String::from).collect();
    fields[6] = format!("{}", fields[6].parse::<f64>().unwrap() + 0.5);
    lines[18] = fields.join(",");
    std::fs::write(at("spoiled.csv"), lines.join("\n")).unwrap();
    let run = calibrate(s(&at("spoiled.csv")), &["--noise-mm", "0.05"]);
    assert!(run.status.success());
    let report = String::from_utf8_lossy(&run.stdout);
    assert!(report.contains("line 19: residual 49"), "{report}");

    // Line 25 without its z, its weight kept: refused by line, nothing written.
    fields = lines[24].split(',').map(String::from).collect();
    fields.remove(8);
    lines[24] = fields.join(",");
    std::fs::write(at("missing.csv"), lines.join("\n")).unwrap();
    let run = calibrate(s(&at("missing.csv")), &[]);
    assert_eq!(run.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&run.stderr).contains("line 25: 9 values"));
    assert!(!at("out.toml").exists());

    // A residual five times the stated noise: refused (exit 1), unless forced.
    let run = calibrate(s(&at("m.csv")), &["--noise-mm", "0.01"]);
    assert_eq!(run.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&run.stderr).contains("stated noise"));
    assert!(!at("out.toml").exists());
    let run = calibrate(s(&at("m.csv")), &["--noise-mm", "0.01", "--force"]);
    assert!(run.status.success());
    assert!(at("out.toml").exists());

    // --world-base: Cartesian poses in the tracker's frame, the column box with them.
    let run = calibrate(s(&at("m.csv")), &["--world-base"]);
    assert!(run.status.success());
    let world = load_file(at("out.toml")).unwrap();
    let chain = Chain::new(&world);
    for m in &check {
        let p = chain.forward(&m.q).unwrap().translation.vector;
        assert!((p - m.position).norm() < 0.3e-3);
    }
    let centre = |b: &[f64; 6]| Point3::new(b[0] + b[1], b[2] + b[3], b[4] + b[5]) / 2.0;
    let (old, new) = (nominal.workspace.boxes[0], world.workspace.boxes[0]);
    let moved = placement.pose.inverse() * centre(&old) - centre(&new);
    assert!(moved.norm() < 1e-6, "{moved}");
    std::fs::remove_dir_all(dir).unwrap();
}
