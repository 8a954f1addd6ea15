//! A stop stays a stop, and a goal stays its owner's (issue 33), over UDP with two clients:
//! a stream after another client's `ST` is refused and the arm stays at rest; a goal one
//! client set never moves the arm for another.

use super::sessions::{START, ask, second_client};
use super::*;

/// The jog: 1 cm/s along y.
const ALONG_Y: [f32; 7] = [0.0, 0.01, 0.0, 0.0, 0.0, 0.0, 0.0];

/// The distance between two `PS` positions (m).
fn moved(from: &[f32; 7], to: &[f32; 7]) -> f32 {
    (0..3)
        .map(|k| (to[k] - from[k]).powi(2))
        .sum::<f32>()
        .sqrt()
}

/// ranger-mk1 from the joints, the drives running.
fn ready() -> Option<Sim> {
    let sim = Sim::start_with("ranger-mk1", &["--start", START]);
    if !knows_status(&sim) {
        return None;
    }
    wait_drives(&sim, 2.0);
    Some(sim)
}

/// The reproduction: A streams `TW` every 10 ms, B sends `ST`. Before, A's next twist
/// resumed the stream and the tool moved 9.6 mm in the second after the stop, with `SQ` 2
/// reporting no cause. Now each of A's twists is refused with the reason, naming the stop and
/// the way to resume; the arm stays at rest; `SQ` 2 reports `ST` until A re-arms with a zero
/// twist.
#[test]
fn a_stream_after_another_clients_st_is_refused_and_the_arm_stays_at_rest() {
    let Some(sim) = ready() else {
        return;
    };
    sim.ok("CM", [2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 0);
    let start = sim.ok("PS", [0.0; 7], 0);
    for _ in 0..50 {
        sim.ok("TW", ALONG_Y, 0);
        std::thread::sleep(Duration::from_millis(10));
    }
    assert_eq!(status(&sim)[4], 5.0, "streaming");
    let b = second_client(&sim);
    assert!(matches!(ask(&b, "ST", [0.0; 7], 0), Answer::Reply(c, ..) if &c == b"TS"));
    // A's jog keeps sending for a second: refused every time.
    let mut settled = None;
    let started = Instant::now();
    while started.elapsed() < Duration::from_secs(1) {
        assert_eq!(sim.text("TW", ALONG_Y, 0), "ER20 Cmd TW after ST: send 0");
        if settled.is_none() && started.elapsed() > Duration::from_millis(300) {
            settled = Some(sim.ok("PS", [0.0; 7], 0));
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    let settled = settled.unwrap();
    let end = sim.ok("PS", [0.0; 7], 0);
    eprintln!(
        "stream then ST: {:.2} mm before the stop settled, {:.4} mm in the 0.7 s after",
        1e3 * moved(&start, &settled),
        1e3 * moved(&settled, &end)
    );
    assert!(moved(&start, &settled) > 0.001, "the stream moved the tool");
    assert!(
        moved(&settled, &end) < 2e-5,
        "the arm moved on after the stop"
    );
    assert_eq!(status(&sim)[4], 0.0, "holding");
    assert_eq!(stop_cause(&sim)[..2], [1.0, 0.0], "SQ 2 keeps ST");
    // A re-arms on purpose: a zero twist, then its jog moves the arm again.
    sim.ok("TW", [0.0; 7], 0);
    assert_eq!(stop_cause(&sim)[0], 0.0, "a new motion clears the cause");
    for _ in 0..30 {
        sim.ok("TW", ALONG_Y, 0);
        std::thread::sleep(Duration::from_millis(10));
    }
    assert!(moved(&end, &sim.ok("PS", [0.0; 7], 0)) > 0.0005);
}

/// The reproduction: A sends `jG qA`; B (the arm at rest) sends `jG qB`; A sends `jB`.
/// Before, the arm drove to qB. Now B's goal went with B's control: A's `jB` is refused with
/// `holder changed` and the arm does not move; A's goal sent again runs to qA.
#[test]
fn a_goal_set_by_one_client_never_moves_the_arm_for_another() {
    let Some(sim) = ready() else {
        return;
    };
    sim.ok("CM", [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 0);
    let start = sim.ok("jP", [0.0; 7], 0);
    let (mut q_a, mut q_b) = (start, start);
    q_a[6] = 0.0;
    q_a[0] += 0.3;
    q_b[6] = 0.0;
    q_b[0] -= 0.3;
    sim.ok("jG", q_a, 0);
    let b = second_client(&sim);
    assert!(matches!(ask(&b, "jG", q_b, 0), Answer::Reply(c, ..) if &c == b"Gj"));
    assert_eq!(sim.text("jB", [0.0; 7], 0), "ER20 Cmd jB holder changed");
    std::thread::sleep(Duration::from_millis(500));
    assert_eq!(status(&sim)[4], 0.0, "nothing moves");
    assert_eq!(sim.ok("jP", [0.0; 7], 0)[0], start[0], "never towards qB");
    sim.ok("jG", q_a, 0);
    sim.start_motion("jB");
    sim.wait_joints(&q_a[..6], 10.0);
}
