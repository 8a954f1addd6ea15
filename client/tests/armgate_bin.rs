//! The `armgate` binary end to end, against a scripted fake controller on 127.0.0.1:0: exit
//! codes, rejections with hints, and notices printed to stderr.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

use std::net::UdpSocket;
use std::process::{Command, Output};
use std::thread::JoinHandle;
use std::time::Duration;

/// A fake controller answering `script(request)` for `n` requests, then ending.
fn fake(n: usize, script: fn(&[u8]) -> Vec<Vec<u8>>) -> (String, JoinHandle<()>) {
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    socket
        .set_read_timeout(Some(Duration::from_secs(5)))
        .unwrap();
    let addr = socket.local_addr().unwrap().to_string();
    let thread = std::thread::spawn(move || {
        let mut buf = [0; 64];
        for _ in 0..n {
            let Ok((len, from)) = socket.recv_from(&mut buf) else {
                return;
            };
            for reply in script(&buf[..len]) {
                socket.send_to(&reply, from).unwrap();
            }
        }
    });
    (addr, thread)
}

fn text(s: &str) -> Vec<u8> {
    let mut b = s.as_bytes().to_vec();
    b.resize(31, 0);
    b
}

fn echo(request: &[u8]) -> Vec<u8> {
    let mut r = request[..31].to_vec();
    r.swap(0, 1);
    r
}

fn armgate(addr: &str, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_armgate"))
        .args(["--addr", addr, "--timeout", "100ms", "--retries", "1"])
        .args(args)
        .env_remove("ARMGATE_ADDR")
        .output()
        .unwrap()
}

#[test]
fn a_rejection_exits_1_with_the_text_a_hint_and_the_notices() {
    let (addr, thread) = fake(2, |request| match &request[..2] {
        b"GT" => vec![text("WN12 Joint limit."), echo(request)],
        _ => vec![text("ER20 Cmd BG rejected")],
    });
    let out = armgate(&addr, &["move", "0.5", "-0.2", "0.4", "0", "0", "0"]);
    thread.join().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("armgate: ER20 Cmd BG rejected"), "{stderr}");
    assert!(stderr.contains("hint: needs Cartesian mode"), "{stderr}");
    assert!(stderr.contains("notice: WN12 Joint limit."), "{stderr}");
}

#[test]
fn no_reply_exits_2() {
    let (addr, thread) = fake(2, |_| vec![]);
    let out = armgate(&addr, &["pose"]);
    thread.join().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("no reply to PS after 2 attempt(s)"),
        "{stderr}"
    );
}

#[test]
fn send_prints_the_reply() {
    let (addr, thread) = fake(1, |request| vec![echo(request)]);
    let out = armgate(&addr, &["send", "CM", "2"]);
    thread.join().unwrap();
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(
        String::from_utf8_lossy(&out.stdout),
        "MC  2.000000 0.000000 0.000000 0.000000 0.000000 0.000000 0.000000  index 0\n"
    );
}

#[test]
fn help_explains_the_commands() {
    let out = Command::new(env!("CARGO_BIN_EXE_armgate"))
        .arg("--help")
        .output()
        .unwrap();
    let help = String::from_utf8_lossy(&out.stdout);
    for word in ["ARMGATE_ADDR", "teleop", "rectangle.toml", "Exit status"] {
        assert!(help.contains(word), "{word}: {help}");
    }
}

#[test]
fn a_closed_output_pipe_ends_quietly() {
    let (addr, thread) = fake(1, |request| vec![echo(request)]);
    let mut child = Command::new(env!("CARGO_BIN_EXE_armgate"))
        .args(["--addr", &addr, "--timeout", "1s", "send", "CM", "2"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // The reader goes away before anything is written.
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    thread.join().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("Broken pipe"), "{stderr}");
    assert_eq!(out.status.code(), Some(0), "{stderr}");
}

#[test]
fn a_zero_timeout_is_refused() {
    let out = Command::new(env!("CARGO_BIN_EXE_armgate"))
        .args(["--timeout", "0", "pose"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("the timeout must be longer than 0"));
}
