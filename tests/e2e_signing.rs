//! End to end: signed datagrams (docs/safety.md, "Signing") against `armgate-sim --key` and
//! the firmware on Linux (`ARMGATE_KEY_FILE`). A signed client moves the arm; a forged MAC, a
//! captured jG/jB sent again, an old timestamp, a cut-off block, an unsigned datagram and
//! another key's signature are each dropped, counted (`SQ` index 4) and never answered, and
//! the arm does not move.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use armgate_client::Signer;
use armgate_protocol::client::signed::{
    ControllerId, IDENTITY_INDEX, SIGNED_LEN, Signature, Signed as Block, SigningKey,
    timestamp_from_unix_us,
};
use armgate_protocol::client::{Command, Request};

use super::{Answer, Sim, datagram, decode, is_unsolicited, with_joints};

/// A key file in the simulator's directory; the key's bytes.
fn key_file(sim_dir: &str, key: [u8; 32]) -> PathBuf {
    let path =
        std::env::temp_dir().join(format!("armgate-e2e-key-{}-{sim_dir}", std::process::id()));
    let hex: String = key.iter().map(|b| format!("{b:02x}")).collect();
    std::fs::write(&path, format!("# e2e key\n{hex}\n")).unwrap();
    set_mode(&path, 0o600);
    path
}

fn set_mode(path: &std::path::Path, mode: u32) {
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(mode)).unwrap();
}

/// A client that signs with `signer` and reads only answers it can verify.
struct Signed<'a> {
    sim: &'a Sim,
    signer: Signer,
    key: SigningKey,
    /// The timestamp of the last request.
    at: u64,
}

impl<'a> Signed<'a> {
    /// A client on `link` that learns the controller's id from its identity report, as the
    /// clients do.
    fn new(sim: &'a Sim, key: &PathBuf, link: u8) -> Self {
        let mut client = Self::unidentified(sim, key, link);
        let report = client.ok("SQ", [0.0; 7], IDENTITY_INDEX);
        let controller = ControllerId((report[0] as u32) << 16 | report[1] as u32);
        client.signer.set_controller(controller);
        client.key = client.key.for_controller(controller);
        client
    }

    /// A client that signs for any controller (it knows no id).
    fn unidentified(sim: &'a Sim, key: &PathBuf, link: u8) -> Self {
        Self {
            sim,
            signer: Signer::from_file(key, Some(link)).unwrap(),
            key: SigningKey::parse(&std::fs::read_to_string(key).unwrap()).unwrap(),
            at: 0,
        }
    }

    /// `SQ` index 4: the signing counters.
    fn counts(&mut self) -> [f32; 7] {
        self.ok("SQ", [0.0; 7], 4)
    }

    /// The signed datagram of a request (not sent).
    fn sign(&mut self, cmd: &str, values: [f32; 7], index: u8) -> [u8; SIGNED_LEN] {
        let (bytes, at) = self.signer.sign(&datagram(cmd, values, index));
        self.at = at;
        bytes
    }

    /// The next verified answer that is not a notice.
    fn receive(&self) -> Answer {
        loop {
            let mut buf = [0u8; 64];
            let n = self.sim.socket.recv(&mut buf).expect("no signed answer");
            assert_eq!(n, SIGNED_LEN, "answers to signed requests are signed");
            let Some(message) = self.signer.open(&buf[..n], self.at) else {
                // A notice signed before the request (older than it) may still be waiting.
                let block = Block::new_checked(&buf[..n]).unwrap();
                assert!(
                    Signature::parse(&block, &self.key).is_ok(),
                    "forged answer, or for another controller"
                );
                assert!(
                    matches!(decode(&buf[..31]), Answer::Text(t) if is_unsolicited(&t)),
                    "an answer older than its request: {:?}",
                    decode(&buf[..31])
                );
                continue;
            };
            match decode(&message) {
                Answer::Text(t) if is_unsolicited(&t) => continue,
                answer => return answer,
            }
        }
    }

    fn ok(&mut self, cmd: &str, values: [f32; 7], index: u8) -> [f32; 7] {
        let bytes = self.sign(cmd, values, index);
        self.sim.socket.send(&bytes).unwrap();
        match self.receive() {
            Answer::Reply(chars, v, _) => {
                assert_eq!(chars, [cmd.as_bytes()[1], cmd.as_bytes()[0]], "{cmd}");
                v
            }
            Answer::Text(t) => panic!("{cmd}: {t}"),
        }
    }

    /// Polls `SQ` until the drives run.
    fn wait_running(&mut self) {
        let started = Instant::now();
        while self.ok("SQ", [0.0; 7], 0)[1] != 2.0 {
            assert!(
                started.elapsed() < Duration::from_secs(10),
                "drives never ran"
            );
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// Polls `jP` until the joints are at `goal`.
    fn wait_joints(&mut self, goal: &[f32]) {
        let started = Instant::now();
        loop {
            let jp = self.ok("jP", [0.0; 7], 0);
            if jp.iter().zip(goal).all(|(a, b)| (a - b).abs() < 1e-4) {
                return;
            }
            assert!(
                started.elapsed() < Duration::from_secs(20),
                "never reached {goal:?}: at {jp:?}"
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

#[test]
fn only_fresh_datagrams_signed_with_the_key_move_the_arm() {
    let key = key_file("move", [0x5a; 32]);
    let sim = Sim::start_with("ranger-mk1", &["--key", key.to_str().unwrap()]);
    let mut arm = Signed::new(&sim, &key, 1);
    arm.wait_running();
    let home: Vec<f32> = arm.ok("jP", [0.0; 7], 0)[..6].to_vec();
    let mut away = home.clone();
    away[0] += 0.05;
    arm.ok("CM", [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 0);
    // The datagrams an eavesdropper captures: a goal away from home and its start.
    let captured_goal = arm.sign("jG", with_joints(&away, 0.0), 0);
    sim.socket.send(&captured_goal).unwrap();
    assert!(matches!(arm.receive(), Answer::Reply(c, _, _) if &c == b"Gj"));
    let captured_begin = arm.sign("jB", [0.0; 7], 0);
    sim.socket.send(&captured_begin).unwrap();
    assert!(matches!(arm.receive(), Answer::Reply(c, _, _) if &c == b"Bj"));
    arm.wait_joints(&away);
    // Back home, signed.
    arm.ok("jG", with_joints(&home, 0.0), 0);
    let begin_home = arm.sign("jB", [0.0; 7], 0);
    sim.socket.send(&begin_home).unwrap();
    arm.receive();
    arm.wait_joints(&home);
    // The timestamp of the last request served (a jP).
    let served = arm.at;

    // The attacks, each a try to move the arm away again.
    let away_goal = datagram("jG", with_joints(&away, 0.0), 0);
    let mut forged = arm.sign("jG", with_joints(&away, 0.0), 0);
    forged[SIGNED_LEN - 1] ^= 0x01;
    let old = Signature {
        link: 1,
        timestamp: served - 1,
    }
    .emit(&away_goal, &arm.key);
    let truncated = arm.sign("jG", with_joints(&away, 0.0), 0);
    let wrong_key = Signature {
        link: 1,
        timestamp: arm.at + 1,
    }
    .emit(
        &away_goal,
        &SigningKey::new(&[0xa5; 32]).for_controller(arm.key.controller()),
    );
    let attacks: [(&str, &[u8]); 7] = [
        ("forged MAC", &forged),
        ("replayed jG", &captured_goal),
        ("replayed jB", &captured_begin),
        ("old timestamp", &old),
        ("truncated block", &truncated[..SIGNED_LEN - 3]),
        ("unsigned", &away_goal),
        ("wrong key", &wrong_key),
    ];
    for (_, bytes) in attacks {
        sim.socket.send(bytes).unwrap();
        // A tick apart: the firmware's request queue holds at most 4 datagrams of one source
        // (docs/firmware.md), and what it drops never reaches the signature check.
        std::thread::sleep(Duration::from_millis(30));
    }
    // Handled in arrival order: an answer to any attack would come before SQ's.
    let counts = arm.ok("SQ", [0.0; 7], 4);
    assert_eq!(
        counts,
        // Policy 1 (required); 12 signed served (this SQ included); 1 unsigned, 1 truncated,
        // 2 forged (MAC, key), 3 replayed (jG, jB, old) dropped.
        [1.0, arm_served(&counts), 0.0, 1.0, 1.0, 2.0, 3.0],
        "{attacks:?}"
    );
    // Nothing moves: still home, holding, a second later.
    std::thread::sleep(Duration::from_secs(1));
    let jp = arm.ok("jP", [0.0; 7], 0);
    assert!(
        jp.iter().zip(&home).all(|(a, b)| (a - b).abs() < 1e-4),
        "{jp:?}"
    );
    assert_eq!(arm.ok("SQ", [0.0; 7], 0)[4], 0.0, "holding");
    let _ = std::fs::remove_file(&key);
}

/// The signed-served count of an `SQ` 4 reply (it depends on how often the test polled).
fn arm_served(counts: &[f32; 7]) -> f32 {
    assert!(counts[1] >= 8.0, "{counts:?}");
    counts[1]
}

#[test]
fn unsigned_clients_may_read_and_stop_beside_signed_ones_when_allowed() {
    let key = key_file("read", [0x3c; 32]);
    let sim = Sim::start_with(
        "ranger-mk1",
        &["--key", key.to_str().unwrap(), "--allow-unsigned", "read"],
    );
    let mut arm = Signed::new(&sim, &key, 7);
    arm.wait_running();
    // The legacy client reads and stops; its other requests get silence.
    assert!(matches!(sim.request("PS", [0.0; 7], 0), Answer::Reply(c, _, _) if &c == b"SP"));
    assert!(matches!(sim.request("ST", [0.0; 7], 0), Answer::Reply(c, _, _) if &c == b"TS"));
    sim.socket
        .send(&datagram("CM", [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 0))
        .unwrap();
    let counts = arm.ok("SQ", [0.0; 7], 4);
    assert_eq!(
        (counts[0], counts[2], counts[3]),
        (2.0, 2.0, 1.0),
        "{counts:?}"
    );
    let _ = std::fs::remove_file(&key);
}

/// The wall clock as a signature's timestamp.
fn now() -> u64 {
    let unix = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap();
    timestamp_from_unix_us(unix.as_micros() as u64)
}

/// `CM 1`, `jG` 0.05 rad away from `home` on joint 1, `jB`: signed on `link` from `timestamp`.
fn move_sequence(arm: &Signed, link: u8, timestamp: u64, home: &[f32]) -> Vec<[u8; SIGNED_LEN]> {
    let mut away = home.to_vec();
    away[0] += 0.05;
    [
        datagram("CM", [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 0),
        datagram("jG", with_joints(&away, 0.0), 0),
        datagram("jB", [0.0; 7], 0),
    ]
    .iter()
    .zip(0..)
    .map(|(m, k)| {
        Signature {
            link,
            timestamp: timestamp + k,
        }
        .emit(m, &arm.key)
    })
    .collect()
}

/// Sends `datagrams` a tick apart; then asserts that none was answered and the arm still is at
/// `home` a second later.
fn sent_in_vain(arm: &mut Signed, datagrams: &[[u8; SIGNED_LEN]], home: &[f32]) {
    for d in datagrams {
        arm.sim.socket.send(d).unwrap();
        std::thread::sleep(Duration::from_millis(30));
    }
    std::thread::sleep(Duration::from_secs(1));
    // Handled in arrival order: an answer to any of them would come before jP's.
    let jp = arm.ok("jP", [0.0; 7], 0);
    assert!(
        jp.iter().zip(home).all(|(a, b)| (a - b).abs() < 1e-4),
        "the arm moved: {jp:?}"
    );
    assert_eq!(arm.ok("SQ", [0.0; 7], 0)[4], 0.0, "holding");
}

#[test]
fn a_day_old_sequence_on_an_unused_link_is_dropped_and_counted() {
    let key = key_file("day-old", [0x4b; 32]);
    let sim = Sim::start_with("ranger-mk1", &["--key", key.to_str().unwrap()]);
    let mut arm = Signed::new(&sim, &key, 1);
    arm.wait_running();
    let home: Vec<f32> = arm.ok("jP", [0.0; 7], 0)[..6].to_vec();
    let day = 86_400 * 100_000;
    let sequence = move_sequence(&arm, 2, now() - day, &home);
    let before = arm.counts()[6];
    sent_in_vain(&mut arm, &sequence, &home);
    assert_eq!(arm.counts()[6] - before, 3.0, "three dropped as replayed");
    let _ = std::fs::remove_file(&key);
}

#[test]
fn after_a_restart_with_the_state_kept_a_served_sequence_is_dropped() {
    let key = key_file("restart", [0x2d; 32]);
    let state = key.with_extension("state");
    let _ = std::fs::remove_file(&state);
    let args = [
        "--key",
        key.to_str().unwrap(),
        "--state",
        state.to_str().unwrap(),
        "--controller-id",
        "5eed0001",
    ];
    let sim = Sim::start_with("ranger-mk1", &args);
    let mut arm = Signed::new(&sim, &key, 1);
    assert_eq!(arm.key.controller(), ControllerId(0x5eed_0001));
    arm.wait_running();
    let home: Vec<f32> = arm.ok("jP", [0.0; 7], 0)[..6].to_vec();
    let sequence = move_sequence(&arm, 2, now(), &home);
    for d in &sequence {
        sim.socket.send(d).unwrap();
        assert!(matches!(arm.receive(), Answer::Reply(..)));
    }
    // The arm moved; it is back home before the restart.
    let mut away = home.clone();
    away[0] += 0.05;
    arm.wait_joints(&away);
    arm.ok("jG", with_joints(&home, 0.0), 0);
    arm.ok("jB", [0.0; 7], 0);
    arm.wait_joints(&home);
    drop(sim);
    assert!(
        std::fs::read_to_string(&state)
            .unwrap()
            .trim()
            .parse::<u64>()
            .is_ok()
    );

    let sim = Sim::start_with("ranger-mk1", &args);
    // A client whose clock is past the kept reservation (at most 2 s ahead of its last use).
    std::thread::sleep(Duration::from_millis(2100));
    let mut arm = Signed::new(&sim, &key, 3);
    arm.wait_running();
    sent_in_vain(&mut arm, &sequence, &home);
    assert_eq!(arm.counts()[6], 3.0, "three dropped as replayed");
    let _ = std::fs::remove_file(&key);
    let _ = std::fs::remove_file(&state);
}

#[test]
fn a_key_shared_by_two_arms_moves_only_the_one_addressed() {
    if super::firmware().is_some() {
        return; // One firmware at a time: two controllers are two armgate-sims.
    }
    let key = key_file("two-arms", [0x71; 32]);
    let a = Sim::start_with("ranger-mk1", &["--key", key.to_str().unwrap()]);
    let b = Sim::start_with("ranger-mk1", &["--key", key.to_str().unwrap()]);
    let mut arm_a = Signed::new(&a, &key, 1);
    let mut arm_b = Signed::new(&b, &key, 1);
    assert_ne!(arm_a.key.controller(), arm_b.key.controller());
    arm_b.wait_running();
    let home: Vec<f32> = arm_b.ok("jP", [0.0; 7], 0)[..6].to_vec();
    // Arm A's sequence, sent to arm B: forged there.
    let for_a = move_sequence(&arm_a, 2, now(), &home);
    sent_in_vain(&mut arm_b, &for_a, &home);
    assert_eq!(arm_b.counts()[5], 3.0, "three dropped as forged");
    // And A obeys it.
    arm_a.wait_running();
    for d in &for_a[..1] {
        a.socket.send(d).unwrap();
        assert!(matches!(arm_a.receive(), Answer::Reply(c, _, _) if &c == b"MC"));
    }
    let _ = std::fs::remove_file(&key);
}

#[test]
fn a_signed_stop_on_a_shared_link_from_a_slower_clock_is_obeyed_and_answered() {
    let key = key_file("slow-stop", [0x66; 32]);
    let sim = Sim::start_with("ranger-mk1", &["--key", key.to_str().unwrap()]);
    let mut arm = Signed::new(&sim, &key, 1);
    arm.wait_running();
    let home: Vec<f32> = arm.ok("jP", [0.0; 7], 0)[..6].to_vec();
    let mut far = home.clone();
    far[0] += 0.4;
    arm.ok("CM", [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 0);
    arm.ok("jG", with_joints(&far, 0.0), 0);
    arm.ok("jB", [0.0; 7], 0);
    assert_ne!(arm.ok("SQ", [0.0; 7], 0)[4], 0.0, "moving");
    // Another operator on link 1 too, its clock 3 s behind.
    let stop = Signature {
        link: 1,
        timestamp: arm.at - 300_000,
    }
    .emit(&datagram("ST", [0.0; 7], 0), &arm.key);
    sim.socket.send(&stop).unwrap();
    let mut buf = [0u8; 64];
    let n = sim.socket.recv(&mut buf).expect("the stop is answered");
    let message = arm
        .signer
        .open(&buf[..n], arm.at - 300_000)
        .expect("signed answer");
    assert!(matches!(decode(&message), Answer::Reply(c, _, _) if &c == b"TS"));
    let started = Instant::now();
    while arm.ok("SQ", [0.0; 7], 0)[4] != 0.0 {
        assert!(started.elapsed() < Duration::from_secs(5), "never stopped");
        std::thread::sleep(Duration::from_millis(50));
    }
    let jp = arm.ok("jP", [0.0; 7], 0);
    assert!(
        (jp[0] - far[0]).abs() > 0.05,
        "stopped short of the goal: {jp:?}"
    );
    assert_eq!(arm.counts()[6], 0.0, "nothing dropped");
    let _ = std::fs::remove_file(&key);
}

#[test]
fn a_client_without_the_id_is_served_only_the_identity_request() {
    let key = key_file("any", [0x19; 32]);
    let sim = Sim::start_with("ranger-mk1", &["--key", key.to_str().unwrap()]);
    let mut any = Signed::unidentified(&sim, &key, 4);
    let bytes = any.sign("CM", [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 0);
    sim.socket.send(&bytes).unwrap();
    std::thread::sleep(Duration::from_millis(100));
    let mut arm = Signed::new(&sim, &key, 5);
    assert_eq!(arm.counts()[5], 1.0, "CM for any controller: forged");
    let _ = std::fs::remove_file(&key);
}

#[test]
fn an_unsigned_poller_beside_a_signed_holder_gets_no_notices_and_does_not_feed_its_watchdog() {
    let key = key_file("poller", [0x3e; 32]);
    let sim = Sim::start_with(
        "ranger-mk1",
        &["--key", key.to_str().unwrap(), "--allow-unsigned", "read"],
    );
    let mut arm = Signed::new(&sim, &key, 7);
    arm.wait_running();
    let home: Vec<f32> = arm.ok("jP", [0.0; 7], 0)[..6].to_vec();
    let mut far = home.clone();
    far[0] += 0.5;
    arm.ok("CM", [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 0);
    arm.ok("WD", [300.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 0);
    arm.ok("jG", with_joints(&far, 0.0), 0);
    arm.ok("jB", [0.0; 7], 0);
    // The signed client goes silent; an unsigned poller polls from its very address (the
    // same socket) every 50 ms.
    let mut signed_notices = Vec::new();
    let started = Instant::now();
    while started.elapsed() < Duration::from_millis(1500) {
        sim.socket.send(&datagram("PS", [0.0; 7], 0)).unwrap();
        std::thread::sleep(Duration::from_millis(50));
        let mut buf = [0u8; 64];
        sim.socket.set_nonblocking(true).unwrap();
        while let Ok(n) = sim.socket.recv(&mut buf) {
            if n == SIGNED_LEN {
                let message = arm
                    .signer
                    .open(&buf[..n], 0)
                    .expect("a notice signed with the key");
                signed_notices.push(decode(&message));
            } else {
                // Unsigned: only the poller's answers, never a notice.
                assert!(matches!(decode(&buf[..n]), Answer::Reply(c, _, _) if &c == b"SP"));
            }
        }
        sim.socket.set_nonblocking(false).unwrap();
    }
    assert!(
        signed_notices
            .iter()
            .any(|n| matches!(n, Answer::Text(t) if t.starts_with("ER41"))),
        "the watchdog fired, told signed: {signed_notices:?}"
    );
    let jp = arm.ok("jP", [0.0; 7], 0);
    assert!(
        (jp[0] - far[0]).abs() > 0.05,
        "stopped short of the goal: {jp:?}"
    );
    let _ = std::fs::remove_file(&key);
}

#[test]
fn two_clients_started_with_default_options_sign_on_distinct_links_and_nothing_is_dropped() {
    let key = key_file("two-clients", [0x2b; 32]);
    let sim = Sim::start_with("ranger-mk1", &["--key", key.to_str().unwrap()]);
    let addr = sim.socket.peer_addr().unwrap();
    let config = armgate_client::ClientConfig {
        timeout: Duration::from_secs(2),
        ..armgate_client::ClientConfig::default()
    };
    let client = || {
        let mut client = armgate_client::Client::connect_with(addr, config.clone()).unwrap();
        client.set_signer(Some(Signer::from_file(&key, None).unwrap()));
        client
    };
    let (mut a, mut b) = (client(), client());
    // Both ask at once; each gets a link of its own.
    let (ra, rb) = (a.identify().unwrap(), b.identify().unwrap());
    assert_eq!(ra.controller, rb.controller);
    let links = [a.signer().unwrap().link(), b.signer().unwrap().link()];
    assert_ne!(links[0], links[1], "{links:?}");
    // Both poll at the same time, each from its own thread: every request answered at once.
    let threads: Vec<_> = [a, b]
        .into_iter()
        .map(|mut c| {
            std::thread::spawn(move || {
                for _ in 0..40 {
                    c.status().unwrap();
                }
                c
            })
        })
        .collect();
    let mut clients: Vec<_> = threads.into_iter().map(|t| t.join().unwrap()).collect();
    let counts = armgate_protocol::client::signed::SigningReport::from_reply(
        &clients[0]
            .request(armgate_protocol::client::Request {
                command: armgate_protocol::client::Command::Status,
                values: [0.0; 7],
                index: 4,
            })
            .unwrap(),
    )
    .unwrap();
    assert_eq!(counts.dropped(), 0, "{counts:?}");
    assert_eq!(clients[0].identify().unwrap().shared_links, 0);
    let _ = std::fs::remove_file(&key);
}

#[test]
fn a_key_file_others_may_read_is_refused_with_the_chmod_that_fixes_it() {
    if super::firmware().is_some() {
        return; // armgate-sim's option; the firmware on Linux reads the key the same way.
    }
    let key = key_file("mode", [0x55; 32]);
    set_mode(&key, 0o640);
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_armgate-sim"))
        .current_dir(root)
        .args(["--listen", "127.0.0.1:0", "--duration", "0", "--key"])
        .arg(&key)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains(&format!("(mode 640): chmod 600 {}", key.display())),
        "{stderr}"
    );
    assert!(!stderr.contains("5555"), "never the key: {stderr}");
    let _ = std::fs::remove_file(&key);
}

#[test]
fn right_after_a_restart_the_client_resends_until_the_reservation_passes_and_is_served() {
    let key = key_file("restart-resend", [0x3e; 32]);
    let state = key.with_extension("state");
    let _ = std::fs::remove_file(&state);
    let args = [
        "--key",
        key.to_str().unwrap(),
        "--state",
        state.to_str().unwrap(),
        "--controller-id",
        "5eed0002",
    ];
    // The client's defaults: 4 sends 0.2 s apart, less than the 2 s a restart refuses for.
    let client = |sim: &Sim| {
        let addr = sim.socket.peer_addr().unwrap();
        let mut client = armgate_client::Client::connect(addr).unwrap();
        client.set_signer(Some(Signer::from_file(&key, Some(1)).unwrap()));
        client
    };
    let sim = Sim::start_with("ranger-mk1", &args);
    Signed::new(&sim, &key, 2).wait_running();
    client(&sim).pose().unwrap();
    drop(sim);
    let sim = Sim::start_with("ranger-mk1", &args);
    // Its first sends are refused (not newer than the reservation kept before the restart);
    // it resends, signed anew, until they are newer.
    let mut after = client(&sim);
    after.pose().unwrap();
    let report = after
        .request(Request {
            command: Command::Status,
            values: [0.0; 7],
            index: 4,
        })
        .unwrap();
    assert!(
        report.values[6] >= 1.0,
        "refused first: {:?}",
        report.values
    );
    let _ = std::fs::remove_file(&key);
    let _ = std::fs::remove_file(&state);
}
