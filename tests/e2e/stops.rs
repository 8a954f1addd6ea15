//! A stop stays a stop, and a goal stays its owner's (issue 33), over UDP with two clients:
//! a stream after another client's `ST`, or resumed after its own timeout, is refused and the
//! arm stays at rest; a goal one client set never moves the arm for another.

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

/// A network stall: A's twists pause for longer than the stream's timeout, then resume (the
/// delayed datagrams arrive). The stream timed out and that latches: every resumed twist is
/// refused naming the timeout, the arm stays at rest, `SQ` 2 reports cause 6; a zero twist
/// re-arms and the jog moves the arm again.
#[test]
fn a_stream_resumed_after_its_timeout_is_refused_and_the_arm_stays_at_rest() {
    let Some(sim) = ready() else {
        return;
    };
    sim.ok("CM", [2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 0);
    let start = sim.ok("PS", [0.0; 7], 0);
    for _ in 0..30 {
        sim.ok("TW", ALONG_Y, 0);
        std::thread::sleep(Duration::from_millis(10));
    }
    // The stall: five times the timeout (3 periods of 19.44 ms), long enough to come to rest.
    std::thread::sleep(Duration::from_millis(300));
    let stalled = sim.ok("PS", [0.0; 7], 0);
    assert!(
        moved(&start, &stalled) > 0.0001,
        "the stream moved the tool"
    );
    for _ in 0..50 {
        assert_eq!(sim.text("TW", ALONG_Y, 0), "ER20 Cmd TW after idle: send 0");
        std::thread::sleep(Duration::from_millis(10));
    }
    let end = sim.ok("PS", [0.0; 7], 0);
    assert!(
        moved(&stalled, &end) < 2e-5,
        "a delayed twist moved the arm"
    );
    assert_eq!(status(&sim)[4], 0.0, "holding");
    assert_eq!(stop_cause(&sim)[0], 6.0, "SQ 2 keeps the stream timeout");
    sim.ok("TW", [0.0; 7], 0);
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

/// The robot file's own Cartesian limits (0.03 m/s, 0.01 m/s² on each axis), not the faster
/// ones the other tests use: the line then has a cruise of 0.3 s, and a stop at its
/// middle runs into the line's own deceleration phase.
fn as_shipped(text: String) -> String {
    text.replace(
        "max_velocity = [0.1, 0.1, 0.1, 0.3, 0.3, 0.3]",
        "max_velocity = [0.03, 0.03, 0.03, 0.05, 0.05, 0.05]",
    )
    .replace(
        "max_acceleration = [0.2, 0.2, 0.2, 0.5, 0.5, 0.5]",
        "max_acceleration = [0.01, 0.01, 0.01, 0.05, 0.05, 0.05]",
    )
}

/// The Cartesian set-points (x, y, z) of `state.csv`, once the last three are equal.
fn logged_setpoints(sim: &Sim) -> Vec<[f64; 3]> {
    let logs = sim._dir.0.join("logs").join("state.csv");
    let started = Instant::now();
    loop {
        let rows = csv_rows(&logs);
        let points: Vec<[f64; 3]> = rows[1..]
            .iter()
            .filter(|r| !r[21].is_empty())
            .map(|r| [21, 22, 23].map(|k| r[k].parse().unwrap()))
            .collect();
        if points.len() > 3 && points[points.len() - 3..].windows(2).all(|w| w[0] == w[1]) {
            return points;
        }
        assert!(
            started.elapsed() < Duration::from_secs(5),
            "the log never shows the set-point at rest"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
}

/// The case: ranger-mk1 from its joints, a line by (0.10, −0.10, 0.05) m, `ST` at
/// cruise. Before, the set-point decelerated at 1.97 × the per-axis `max_acceleration` on x
/// and y. Now each axis stays within 1.00 × (the state log's set-points, armgate-sim), and the
/// tool comes to rest on the line (both targets).
#[test]
fn st_in_a_diagonal_cartesian_line_at_cruise_brakes_within_each_axis_limit() {
    let sim = Sim::start_edited("ranger-mk1", as_shipped, &["--start", START]);
    if !knows_status(&sim) {
        return;
    }
    wait_drives(&sim, 2.0);
    sim.ok("CM", [2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 0);
    let start = sim.ok("PS", [0.0; 7], 0);
    let by = [0.10f32, -0.10, 0.05];
    let mut goal = start;
    for k in 0..3 {
        goal[k] += by[k];
    }
    sim.ok("GL", goal, 0);
    sim.start_motion("BG");
    // 6.33 s planned: 3 s up to 0.03 m/s on x, 0.33 s of cruise, 3 s down.
    std::thread::sleep(Duration::from_millis(3170));
    sim.null("ST");
    assert!(
        poll_status(&sim, Duration::from_secs(6), |s| s[4] == 0.0),
        "never came to rest"
    );
    std::thread::sleep(Duration::from_millis(300));
    let end = sim.ok("PS", [0.0; 7], 0);
    let length = by.iter().map(|v| v * v).sum::<f32>().sqrt();
    let along = (0..3).map(|k| (end[k] - start[k]) * by[k]).sum::<f32>() / length;
    let off = (moved(&start, &end).powi(2) - along.powi(2))
        .max(0.0)
        .sqrt();
    eprintln!(
        "diagonal line stopped at cruise: {:.1} mm along, {:.3} mm off the line",
        1e3 * along,
        1e3 * off
    );
    assert!(along > 0.03, "{along} m along");
    assert!(off < 1e-4, "{off} m off the line");
    if firmware().is_some() {
        return; // the state log is armgate-sim's
    }
    let points = logged_setpoints(&sim);
    let period = 0.01944;
    let mut peak = [0.0f64; 3];
    for w in points.windows(3) {
        for k in 0..3 {
            let a = (w[2][k] - 2.0 * w[1][k] + w[0][k]) / (period * period);
            peak[k] = peak[k].max(a.abs() / 0.01);
        }
    }
    eprintln!("peak set-point acceleration / max_acceleration per axis: {peak:.4?}");
    // The log's nine decimals carry 2e-9 m of rounding into each second difference.
    assert!(peak.iter().all(|p| *p <= 1.0 + 2e-3), "{peak:?}");
}

/// A `VE`'s legs are checked a few points a tick (the line check in slices, as `KG`'s search):
/// while 20 legs are checked, another client's `SQ` is answered and its `ST` cancels the check
/// (`ER42 Cmd VE cancelled by ST`); the arm never moves.
#[test]
fn a_sequence_still_being_checked_answers_another_client_and_its_st_cancels_it() {
    let Some(sim) = ready() else {
        return;
    };
    sim.ok("CM", [2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 0);
    let start = sim.ok("PS", [0.0; 7], 0);
    // Via points 5 cm apart, to and fro: 20 legs of 16 points or more each.
    for slot in 0..20u8 {
        let mut via = start;
        via[0] += if slot % 2 == 0 { 0.05 } else { 0.0 };
        via[6] = 0.0;
        sim.ok("VP", via, slot);
    }
    sim.socket.send(&datagram("VE", [0.0; 7], 0)).unwrap();
    let b = second_client(&sim);
    let read = ask(&b, "SQ", [0.0; 7], 0);
    assert!(
        matches!(read, Answer::Reply(c, ..) if &c == b"QS"),
        "{read:?}"
    );
    assert!(matches!(ask(&b, "ST", [0.0; 7], 0), Answer::Reply(c, ..) if &c == b"TS"));
    match sim.receive_reply() {
        Answer::Text(t) => assert_eq!(t, "ER42 Cmd VE cancelled by ST"),
        other => panic!("VE answered {other:?}"),
    }
    std::thread::sleep(Duration::from_millis(300));
    let end = sim.ok("PS", [0.0; 7], 0);
    assert!(moved(&start, &end) < 1e-5, "the arm moved");
    assert_eq!(status(&sim)[4], 0.0, "holding");
}
