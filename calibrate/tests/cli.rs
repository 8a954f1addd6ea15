//! `armgate-calibrate` end to end: plan, simulate, calibrate through files, and its errors.
#![allow(clippy::unwrap_used, clippy::panic)] // helpers of tests: a panic is a failed test

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use armgate_core::config::load_file;

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
