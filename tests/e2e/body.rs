//! The whole arm near the rover's body over UDP (issue 35): a twist stream towards the column
//! slows as the gap shrinks and holds before contact, told once with the link and the box;
//! `SQ` index 7 reports the nearest gap and its pair to either client.

use super::sessions::{ask, second_client};
use super::*;

/// ranger-mk1 with the tool's line 10 cm above the column's edge (its wrist centre over the
/// column, the tool point outside it): on the way from its ready pose into the column.
const ABOVE_THE_COLUMN: &str = "0.852,1.012,1.223,-2.396,3.231,-1.111";
/// 2 cm/s straight down.
const DOWN: [f32; 7] = [0.0, 0.0, -0.02, 0.0, 0.0, 0.0, 0.0];

fn ready() -> Option<Sim> {
    let sim = Sim::start_with("ranger-mk1", &["--start", ABOVE_THE_COLUMN]);
    if !knows_status(&sim) {
        return None;
    }
    wait_drives(&sim, 2.0);
    Some(sim)
}

/// Sends a request and returns its reply's values, keeping the unsolicited texts that come
/// before it in `notices`.
fn exchange(sim: &Sim, cmd: &str, values: [f32; 7], notices: &mut Vec<String>) -> [f32; 7] {
    sim.socket.send(&datagram(cmd, values, 0)).unwrap();
    loop {
        let mut buf = [0u8; 64];
        assert_eq!(sim.socket.recv(&mut buf).expect("no reply"), 31);
        match decode(&buf) {
            Answer::Text(t) if is_unsolicited(&t) => notices.push(t),
            Answer::Reply(chars, v, _) if chars == [cmd.as_bytes()[1], cmd.as_bytes()[0]] => {
                return v;
            }
            other => panic!("{cmd}: {other:?}"),
        }
    }
}

/// `SQ` index 7 asked on `socket`: the gap (m), the link, the kind of obstacle (0 box, 1
/// link, 2 bounds), its number, the margin.
fn nearest(socket: &UdpSocket) -> [f32; 7] {
    match ask(socket, "SQ", [0.0; 7], 7) {
        Answer::Reply(chars, v, 7) if &chars == b"QS" => v,
        other => panic!("SQ 7: {other:?}"),
    }
}

/// A jog down towards the column's edge at 2 cm/s, sent every 10 ms: the tool's speed (read
/// by a second client's `PS` every 20 ms, so the stream's own sends stay on time) falls over the
/// last centimetre, the arm comes to rest short of the column and stays there while the same
/// twist keeps coming; one `WN13 Held: L6 hits B1` names the tool's link and the box; `SQ` 7
/// then names the same pair, about a millimetre apart.
#[test]
fn a_twist_stream_towards_the_column_slows_and_holds_before_contact() {
    let Some(sim) = ready() else {
        return;
    };
    sim.ok("CM", [2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 0);
    let reader = second_client(&sim);
    let done = std::sync::atomic::AtomicBool::new(false);
    // Ends the poll when the stream's loop ends, also by a failed assertion.
    struct Done<'a>(&'a std::sync::atomic::AtomicBool);
    impl Drop for Done<'_> {
        fn drop(&mut self) {
            self.0.store(true, std::sync::atomic::Ordering::Relaxed);
        }
    }
    let started = Instant::now();
    let mut notices = Vec::new();
    // (seconds, z) of the tool.
    let trace: Vec<(f32, f32)> = std::thread::scope(|scope| {
        let poll = scope.spawn(|| {
            let mut trace = Vec::new();
            while !done.load(std::sync::atomic::Ordering::Relaxed) {
                if let Answer::Reply(_, ps, _) = ask(&reader, "PS", [0.0; 7], 0) {
                    trace.push((started.elapsed().as_secs_f32(), ps[2]));
                }
                std::thread::sleep(Duration::from_millis(20));
            }
            trace
        });
        let stop_polling = Done(&done);
        let mut held_at = None;
        while started.elapsed() < Duration::from_secs(12) {
            exchange(&sim, "TW", DOWN, &mut notices);
            if notices.iter().any(|n| n.starts_with("WN13")) {
                held_at.get_or_insert(Instant::now());
            }
            // Held: go on sending for a second.
            if held_at.is_some_and(|t| t.elapsed() > Duration::from_secs(1)) {
                break;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        drop(stop_polling);
        poll.join().unwrap()
    });
    let held: Vec<_> = notices.iter().filter(|n| n.starts_with("WN13")).collect();
    assert_eq!(held, ["WN13 Held: L6 hits B1"], "{notices:?}");
    assert!(
        !notices.iter().any(|n| n.starts_with("ER21")),
        "no stop: {notices:?}"
    );
    // Speeds over 0.2 s windows, from the start of the stream to the end.
    let speeds: Vec<(f32, f32)> = trace
        .windows(2)
        .scan(None::<(f32, f32)>, |window, pair| {
            let start = window.get_or_insert(pair[0]);
            if pair[1].0 - start.0 < 0.2 {
                return Some(None);
            }
            let speed = (start.1 - pair[1].1) / (pair[1].0 - start.0);
            *window = Some(pair[1]);
            Some(Some((pair[1].1, speed)))
        })
        .flatten()
        .collect();
    eprintln!("tool z and speed over 0.2 s windows: {speeds:?}");
    let peak = speeds.iter().map(|(_, v)| *v).fold(0.0, f32::max);
    assert!(peak > 0.015, "never near 2 cm/s: {speeds:?}");
    // At rest for the last half second while the twist kept coming.
    let (end_t, end_z) = trace[trace.len() - 1];
    let resting = trace.iter().filter(|(t, _)| end_t - t < 0.5);
    assert!(
        resting.clone().count() > 5 && resting.clone().all(|(_, z)| (z - end_z).abs() < 1e-5),
        "moved on while held: {trace:?}"
    );
    // The last windows before rest: slower and slower, well below the peak.
    let moving: Vec<_> = speeds.iter().filter(|(_, v)| *v > 1e-4).collect();
    let tail = &moving[moving.len().saturating_sub(3)..];
    assert!(tail.windows(2).all(|w| w[1].1 < w[0].1), "{tail:?}");
    assert!(tail[tail.len() - 1].1 < 0.6 * peak, "{tail:?}");
    let report = nearest(&sim.socket);
    assert_eq!(report[1..5], [6.0, 0.0, 1.0, 0.0], "{report:?}");
    assert!(
        report[0] > 0.0 && report[0] < 0.003,
        "held {} mm from the box at z {end_z}",
        report[0] * 1e3
    );
}

/// `SQ` 7 is a read: answered to any client, the controlling one and another alike, with the
/// same gap and pair; at the start pose the tool's line is 10 cm above the column's edge.
#[test]
fn the_nearest_gap_is_answered_to_either_client() {
    let Some(sim) = ready() else {
        return;
    };
    sim.ok("CM", [2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 0);
    let b = second_client(&sim);
    let a = nearest(&sim.socket);
    assert_eq!(a, nearest(&b));
    assert_eq!(a[1..], [6.0, 0.0, 1.0, 0.0, 0.0, 0.0], "{a:?}");
    assert!((a[0] - 0.0997).abs() < 0.002, "{a:?}");
    assert_eq!(sim.text("SQ", [0.0; 7], 8), "ER24 Cmd SQ bad index");
}
