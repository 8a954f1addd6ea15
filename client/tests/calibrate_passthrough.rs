//! `armgate calibrate …` runs `armgate-calibrate` from next to `armgate` (or PATH), passing the
//! arguments and the exit status through, and says how to build it when it is missing.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// A private directory holding a copy of `armgate`.
fn armgate_in(dir_name: &str) -> (PathBuf, PathBuf) {
    let dir = std::env::temp_dir().join(format!("{dir_name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let exe = dir.join("armgate");
    std::fs::copy(env!("CARGO_BIN_EXE_armgate"), &exe).unwrap();
    (dir, exe)
}

fn run(exe: &Path, args: &[&str]) -> std::process::Output {
    // Not as if run by `cargo run -p armgate-client`, which would build the tool instead.
    Command::new(exe)
        .args(args)
        .env("PATH", "")
        .env_remove("CARGO")
        .output()
        .unwrap()
}

// One test, so that no other thread of this process forks while a file about to be executed is
// still open for writing (that child would make the exec fail with ETXTBSY).
#[cfg(unix)]
#[test]
fn passes_through_or_explains_what_is_missing() {
    use std::os::unix::fs::PermissionsExt;

    let (dir, exe) = armgate_in("armgate-calibrate-missing");
    let out = run(&exe, &["calibrate", "--robot", "r.toml"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("cargo build -p armgate-calibrate"), "{err}");

    // With a stand-in tool next to armgate: arguments and exit status pass through.
    let tool = dir.join("armgate-calibrate");
    std::fs::write(&tool, "#!/bin/sh\necho \"got: $*\"\nexit 3\n").unwrap();
    std::fs::set_permissions(&tool, std::fs::Permissions::from_mode(0o755)).unwrap();
    let out = run(&exe, &["calibrate", "plan", "--robot", "r.toml", "--help"]);
    assert_eq!(out.status.code(), Some(3));
    assert_eq!(
        String::from_utf8_lossy(&out.stdout),
        "got: plan --robot r.toml --help\n"
    );
    std::fs::remove_dir_all(dir).unwrap();
}
