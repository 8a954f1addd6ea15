//! End to end: signed datagrams (docs/safety.md, "Signing") against `armgate-sim --key` and
//! the firmware on Linux (`ARMGATE_KEY_FILE`). A signed client moves the arm; a forged MAC, a
//! captured jG/jB sent again, an old timestamp, a cut-off block, an unsigned datagram and
//! another key's signature are each dropped, counted (`SQ` index 4) and never answered, and
//! the arm does not move.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use armgate_client::Signer;
use armgate_protocol::client::signed::{SIGNED_LEN, Signature, Signed as Block, SigningKey};

use super::{Answer, Sim, datagram, decode, is_unsolicited, with_joints};

/// A key file in the simulator's directory; the key's bytes.
fn key_file(sim_dir: &str, key: [u8; 32]) -> PathBuf {
    let path =
        std::env::temp_dir().join(format!("armgate-e2e-key-{}-{sim_dir}", std::process::id()));
    let hex: String = key.iter().map(|b| format!("{b:02x}")).collect();
    std::fs::write(&path, format!("# e2e key\n{hex}\n")).unwrap();
    path
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
    fn new(sim: &'a Sim, key: &PathBuf, link: u8) -> Self {
        Self {
            sim,
            signer: Signer::from_file(key, link).unwrap(),
            key: SigningKey::parse(&std::fs::read_to_string(key).unwrap()).unwrap(),
            at: 0,
        }
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
                assert!(Signature::parse(&block, &self.key).is_ok(), "forged answer");
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
    .emit(
        &away_goal,
        &SigningKey::parse(&std::fs::read_to_string(&key).unwrap()).unwrap(),
    );
    let truncated = arm.sign("jG", with_joints(&away, 0.0), 0);
    let wrong_key = Signature {
        link: 1,
        timestamp: arm.at + 1,
    }
    .emit(&away_goal, &SigningKey::new(&[0xa5; 32]));
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
    }
    // Handled in arrival order: an answer to any attack would come before SQ's.
    let counts = arm.ok("SQ", [0.0; 7], 4);
    assert_eq!(
        counts,
        // Policy 1 (required); 11 signed served (this SQ included); 1 unsigned, 1 truncated,
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
