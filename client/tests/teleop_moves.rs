//! `armgate teleop` moves the arm (issue 37): under `script` (a pty) against armgate-sim
//! (ranger-mk1, simulated arm), its first screen says which key changes the mode (`m mode
//! cartesian`); `j` (joint keys), `m` (joint mode, as the controller then reports) and →
//! (joint 1 one step up, `--step --live`: jG + jB at once) move joint 1, and only it, as
//! another client reads it (`jP`).
//!
//! armgate-sim is `$ARMGATE_SIM`, else `armgate-sim` next to this package's binary (built with
//! cargo if missing), as calibrate/tests/measure_sim.rs finds it.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;

use common::{Reap, wait_for};
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

use armgate_client::{Client, DriveStatus, Mode};

const ARMGATE: &str = env!("CARGO_BIN_EXE_armgate");

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn sim_binary() -> PathBuf {
    if let Some(given) = std::env::var_os("ARMGATE_SIM") {
        return given.into();
    }
    let sim = Path::new(ARMGATE).with_file_name("armgate-sim");
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

/// armgate-sim for ranger-mk1 from a pose with room to move, on a free port.
fn start_sim() -> (Reap, String) {
    let robot = repo().join("robots/ranger-mk1.toml");
    let mut child = Command::new(sim_binary())
        .arg("--robot")
        .arg(robot)
        .args(["--listen", "127.0.0.1:0", "--can", "off"])
        .args(["--start", "1.5708,0.6,-0.4,0.2,1.8,0.1"])
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
    (Reap(child), addr.expect("armgate-sim's address"))
}

#[test]
fn a_key_press_in_teleop_moves_the_arm_and_the_screen_names_the_mode_key() {
    if Command::new("script").arg("--version").output().is_err() {
        eprintln!("skipped: no `script` (util-linux) to give teleop a terminal");
        return;
    }
    let (_sim, addr) = start_sim();
    let mut watcher = Client::connect(addr.as_str()).unwrap();
    assert!(wait_for(Duration::from_secs(20), || watcher
        .status()
        .is_ok_and(|s| s.drives == DriveStatus::Running)));
    let before = watcher.joints(6).unwrap();
    let screen = std::env::temp_dir().join(format!("armgate-teleop-{}.txt", std::process::id()));
    // A pty under a pipe has no size: give it one, or nothing is drawn.
    let teleop = format!("stty cols 120 rows 40; {ARMGATE} --addr {addr} teleop --step --live");
    let script = Command::new("script")
        .args(["-qfec", &teleop])
        .arg(&screen)
        .env("TERM", "xterm")
        .env_remove("ARMGATE_ADDR")
        .env_remove("ARMGATE_KEY_FILE")
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut script = Reap(script);
    let shown = |what: &str| {
        std::fs::read(&screen).is_ok_and(|s| String::from_utf8_lossy(&s).contains(what))
    };
    // The first screen: Cartesian keys, and the key that selects their mode.
    let tail = || {
        let all = String::from_utf8_lossy(&std::fs::read(&screen).unwrap_or_default()).into_owned();
        all.chars()
            .rev()
            .take(3000)
            .collect::<Vec<_>>()
            .into_iter()
            .rev()
            .collect::<String>()
    };
    assert!(
        wait_for(Duration::from_secs(20), || shown("m mode cartesian")),
        "{}",
        tail()
    );
    let mut press = |keys: &[u8]| {
        let stdin = script.0.stdin.as_mut().unwrap();
        stdin.write_all(keys).unwrap();
        stdin.flush().unwrap();
        std::thread::sleep(Duration::from_millis(300));
    };
    // Joint keys (the screen is then drawn as changes to the first: only the first is
    // whole), and m selects their mode.
    press(b"j");
    press(b"m");
    assert!(wait_for(Duration::from_secs(5), || watcher
        .status()
        .is_ok_and(|s| s.mode == Mode::Joint)));
    // → : joint 1 one step (0.01 rad) up, sent at once.
    press(b"\x1b[C");
    let moved = wait_for(Duration::from_secs(10), || {
        watcher.joints(6).is_ok_and(|q| q[0] - before[0] > 0.005)
    });
    let after = watcher.joints(6).unwrap();
    press(b"q");
    let _ = std::fs::remove_file(&screen);
    assert!(moved, "joint 1 did not move: {before:?} -> {after:?}");
    for (b, a) in before.iter().zip(&after).skip(1) {
        assert!(
            (a - b).abs() < 1e-3,
            "only joint 1 moves: {before:?} -> {after:?}"
        );
    }
}
