//! `armgate teleop` on SIGHUP, on a terminal that closes and on `q`: it sends `ST` before it
//! exits (docs/safety.md), unless the controller names another client as the holder of the arm
//! (issue 33): a teleop opened to watch leaves another operator's motion alone. teleop needs a
//! terminal: it runs under `script`, which gives it a pty, against a fake controller on
//! 127.0.0.1:0 that answers every request and notes each one.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod common;

use common::{Reap, wait_for};
use std::net::UdpSocket;
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// Who the fake controller's session report (`SQ` 3) names as the holder of the arm.
#[derive(Clone, Copy)]
enum Holding {
    /// Nobody (the echo of the request's zeros).
    Nobody,
    /// Another client, 10.0.0.9:4000.
    Stranger,
    /// The client that sent the first request (teleop's poller).
    Teleop,
}

/// A fake controller: every request is answered with its characters reversed and its values
/// and index echoed (`SQ` 3 as `holding` says), and its characters noted, until `stop` is set.
fn fake(stop: Arc<AtomicBool>, holding: Holding) -> (String, Arc<Mutex<Vec<String>>>) {
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    socket
        .set_read_timeout(Some(Duration::from_millis(50)))
        .unwrap();
    let addr = socket.local_addr().unwrap().to_string();
    let seen = Arc::new(Mutex::new(Vec::new()));
    std::thread::spawn({
        let seen = seen.clone();
        move || {
            let mut buf = [0; 64];
            let mut first = None;
            while !stop.load(Ordering::Relaxed) {
                let Ok((len, from)) = socket.recv_from(&mut buf) else {
                    continue;
                };
                if len < 31 {
                    continue;
                }
                let first = *first.get_or_insert(from);
                seen.lock()
                    .unwrap()
                    .push(String::from_utf8_lossy(&buf[..2]).into_owned());
                let mut reply = buf[..31].to_vec();
                reply.swap(0, 1);
                let holder: Option<std::net::SocketAddrV4> = match (holding, first) {
                    (Holding::Nobody, _) => None,
                    (Holding::Stranger, _) => Some("10.0.0.9:4000".parse().unwrap()),
                    (Holding::Teleop, std::net::SocketAddr::V4(a)) => Some(a),
                    (Holding::Teleop, _) => None,
                };
                if &buf[..2] == b"SQ"
                    && buf[30] == 3
                    && let Some(holder) = holder
                {
                    let ip = u32::from(*holder.ip());
                    let values = [
                        2.0f32,
                        (ip >> 16) as f32,
                        (ip & 0xffff) as f32,
                        f32::from(holder.port()),
                        0.0,
                        0.0,
                        2.0,
                    ];
                    for (k, v) in values.iter().enumerate() {
                        reply[2 + 4 * k..6 + 4 * k].copy_from_slice(&v.to_le_bytes());
                    }
                }
                let _ = socket.send_to(&reply, from);
            }
        }
    });
    (addr, seen)
}

/// The process ids below `pid`, depth first.
fn descendants(pid: u32) -> Vec<u32> {
    let children =
        std::fs::read_to_string(format!("/proc/{pid}/task/{pid}/children")).unwrap_or_default();
    children
        .split_whitespace()
        .filter_map(|c| c.parse().ok())
        .flat_map(|c| std::iter::once(c).chain(descendants(c)))
        .collect()
}

/// Runs `armgate teleop` under `script` against a fake controller, ends it with `end` (given
/// `script` and teleop's process id) once it polls, and returns the requests the controller got
/// after that; None without `script`.
fn requests_after(holding: Holding, end: impl FnOnce(&mut Child, u32)) -> Option<Vec<String>> {
    if Command::new("script").arg("--version").output().is_err() {
        eprintln!("skipped: no `script` (util-linux) to give teleop a terminal");
        return None;
    }
    let stop = Arc::new(AtomicBool::new(false));
    let (addr, seen) = fake(stop.clone(), holding);
    let teleop = format!(
        "{} --addr {addr} --joints 6 teleop",
        env!("CARGO_BIN_EXE_armgate")
    );
    // stdin stays open (a pipe): `script` would end at its end.
    let script = Command::new("script")
        .args(["-qec", &teleop, "/dev/null"])
        .env("TERM", "xterm")
        .env_remove("ARMGATE_ADDR")
        .env_remove("ARMGATE_KEY_FILE")
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut script = Reap(script);
    // Running: it polls the controller.
    assert!(
        wait_for(Duration::from_secs(20), || seen.lock().unwrap().len() >= 5),
        "teleop never polled: {:?}",
        seen.lock().unwrap()
    );
    let armgate = descendants(script.0.id())
        .into_iter()
        .find(|pid| {
            std::fs::read_to_string(format!("/proc/{pid}/comm"))
                .is_ok_and(|comm| comm.trim() == "armgate")
        })
        .expect("armgate under script");
    let before = seen.lock().unwrap().len();
    assert!(!seen.lock().unwrap().iter().any(|c| c == "ST"));
    end(&mut script.0, armgate);
    // It exits (or is left a zombie of `script`'s, killed).
    let gone = || {
        std::fs::read_to_string(format!("/proc/{armgate}/stat"))
            .map_or(true, |stat| stat.contains(") Z "))
    };
    assert!(wait_for(Duration::from_secs(10), gone), "teleop still runs");
    stop.store(true, Ordering::Relaxed);
    let after = seen.lock().unwrap()[before..].to_vec();
    Some(after)
}

#[test]
fn teleop_sends_st_on_sighup() {
    let Some(after) = requests_after(Holding::Nobody, |_, armgate| {
        let hangup = Command::new("kill")
            .args(["-HUP", &armgate.to_string()])
            .status()
            .unwrap();
        assert!(hangup.success());
    }) else {
        return;
    };
    eprintln!("after SIGHUP the controller got {after:?}");
    assert!(
        after.iter().any(|c| c == "ST"),
        "no ST after SIGHUP: {after:?}"
    );
}

/// The terminal itself goes (`script`, which holds the pty's other end, is killed): the kernel
/// hangs up teleop's terminal and sends it SIGHUP, and reading the terminal no longer blocks.
#[test]
fn teleop_sends_st_when_its_terminal_closes() {
    let Some(after) = requests_after(Holding::Nobody, |script, _| {
        script.kill().unwrap();
        let _ = script.wait();
    }) else {
        return;
    };
    eprintln!("after its terminal closed the controller got {after:?}");
    assert!(after.iter().any(|c| c == "ST"), "no ST: {after:?}");
}

/// Quits teleop with `q` (typed into its terminal) while the fake names `holding` as holder.
fn quit_while(holding: Holding) -> Option<Vec<String>> {
    requests_after(holding, |script, _| {
        use std::io::Write;
        let stdin = script.stdin.as_mut().unwrap();
        stdin.write_all(b"q").unwrap();
        stdin.flush().unwrap();
    })
}

#[test]
fn teleop_quit_while_another_client_holds_the_arm_leaves_its_motion_alone() {
    let Some(after) = quit_while(Holding::Stranger) else {
        return;
    };
    eprintln!("after q the controller got {after:?}");
    assert!(
        after.iter().any(|c| c == "SQ"),
        "no session asked: {after:?}"
    );
    assert!(!after.iter().any(|c| c == "ST"), "ST sent: {after:?}");
}

#[test]
fn teleop_quit_while_it_holds_the_arm_stops_it() {
    let Some(after) = quit_while(Holding::Teleop) else {
        return;
    };
    eprintln!("after q the controller got {after:?}");
    assert!(after.iter().any(|c| c == "ST"), "no ST: {after:?}");
}
