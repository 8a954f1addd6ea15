//! The simulated Whistle and the virtual bus on their own.
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]
// The seed's home angles are written as it wrote them (1.5708), not as π/2.
#![allow(clippy::approx_constant)]

mod drives_rig;

use armgate_core::drives::{CanBus, DriveEmergency};
use armgate_core::sim::VirtualBus;
use armgate_protocol::can::interpreter::{Index, Mnemonic, Reply, Value};
use armgate_protocol::can::{Emcy, Incoming, Nmt, NmtState, NodeMessage, exact_bits_on_wire};
use drives_rig::frames::{exchange, pt_ring, query, set, whistle};

#[test]
fn frames_take_their_exact_bit_time_and_lower_ids_win() {
    let mut bus = VirtualBus::new(500_000, [whistle(0), whistle(1)]);
    let nmt = Nmt::START_ALL.to_frame();
    bus.try_transmit(&nmt).unwrap();
    // The NMT frame takes its exact length at 2 µs per bit; the drives switch at its end.
    let end = f64::from(exact_bits_on_wire(&nmt)) * 2e-6;
    bus.advance(end - 1e-7).unwrap();
    assert_eq!(
        bus.drive(101).unwrap().nmt_state(),
        NmtState::PreOperational
    );
    bus.advance(end).unwrap();
    assert_eq!(bus.drive(101).unwrap().nmt_state(), NmtState::Operational);
    assert_eq!(bus.stats().frames, 1);
    assert_eq!(bus.stats().bits, u64::from(exact_bits_on_wire(&nmt)));
    // The controller sends in queue order: 102 is asked, and answers, first although 101's
    // identifier is lower.
    let received = exchange(
        &mut bus,
        &[query(102, Mnemonic::PX, 0), query(101, Mnemonic::PX, 0)],
        0.005,
    );
    let from: Vec<u16> = received.iter().map(|f| f.id()).collect();
    assert_eq!(from, [0x2E6, 0x2E5]);
    // Between nodes the lower identifier wins: 101's answer (0x2E5), ready 250 µs after its
    // query, goes before the controller's next queued frame (0x369), not after the queue.
    let queue = [
        query(101, Mnemonic::PX, 0),
        query(105, Mnemonic::PX, 0),
        query(105, Mnemonic::UM, 0),
        query(105, Mnemonic::TI, 1),
    ];
    let bits: Vec<f64> = queue
        .iter()
        .map(|f| f64::from(exact_bits_on_wire(f)))
        .collect();
    let answer_ready = bits[0] * 2e-6 + 250e-6;
    assert!(answer_ready < (bits[0] + bits[1] + bits[2]) * 2e-6);
    // An 8-byte answer takes at most 135 bits; after the fourth query it would end later.
    let won_by = (bits[0] + bits[1] + bits[2] + 135.0) * 2e-6;
    assert!(won_by < (bits.iter().sum::<f64>() + 100.0) * 2e-6);
    let received = exchange(&mut bus, &queue, won_by);
    assert_eq!(received.iter().map(|f| f.id()).collect::<Vec<_>>(), [0x2E5]);
}

#[test]
fn the_drive_answers_what_the_manager_uses() {
    let mut bus = VirtualBus::new(1_000_000, [whistle(2)]);
    exchange(&mut bus, &[Nmt::START_ALL.to_frame()], 0.001);
    let n = 103;
    let answers = exchange(
        &mut bus,
        &[query(n, Mnemonic::UM, 0), query(n, Mnemonic::TI, 1)],
        0.002,
    );
    let values: Vec<Reply> = answers.iter().map(|f| Reply::parse(f).unwrap().1).collect();
    assert_eq!(
        values,
        [
            Reply::Value {
                command: Mnemonic::UM,
                index: Index::ZERO,
                value: Value::Int(5),
            },
            Reply::Value {
                command: Mnemonic::TI,
                index: Index::from(1),
                value: Value::Int(25),
            },
        ]
    );
    // Unknown commands, bad indices, BG with the motor off: the error bit.
    let refused = exchange(
        &mut bus,
        &[query(n, Mnemonic::JV, 0), query(n, Mnemonic::TI, 2)],
        0.002,
    );
    let refused_bg = exchange(&mut bus, &[query(n, Mnemonic::BG, 0)], 0.002);
    for frame in refused.iter().chain(&refused_bg) {
        assert!(matches!(
            Reply::parse(frame).unwrap().1,
            Reply::Error { .. }
        ));
    }
    // UM cannot change with the motor on.
    exchange(&mut bus, &[set(n, Mnemonic::MO, 0, 1)], 0.002);
    let refused = exchange(&mut bus, &[set(n, Mnemonic::UM, 0, 2)], 0.002);
    assert!(matches!(
        Reply::parse(&refused[0]).unwrap().1,
        Reply::Error { .. }
    ));
}

/// Configures a cyclic ring of 6 with `samples` per segment and the queue-low threshold,
/// fills QP[1..=3] with `points`, and begins.
fn begin(bus: &mut VirtualBus, n: u8, samples: i32, queue_low: i32, points: [i32; 3]) {
    pt_ring(bus, n, samples, queue_low);
    for (i, p) in points.iter().enumerate() {
        exchange(bus, &[set(n, Mnemonic::QP, i as u8 + 1, *p)], 0.001);
    }
    exchange(bus, &[set(n, Mnemonic::PT, 0, 1)], 0.001);
    let answer = exchange(bus, &[query(n, Mnemonic::BG, 0)], 0.001);
    assert_eq!(
        Reply::parse(&answer[0]).unwrap().1,
        Reply::Value {
            command: Mnemonic::BG,
            index: Index::ZERO,
            value: Value::Int(0)
        }
    );
}

#[test]
fn pt_motion_passes_through_the_points_then_underflows() {
    let mut bus = VirtualBus::new(1_000_000, [whistle(0)]);
    exchange(&mut bus, &[Nmt::START_ALL.to_frame()], 0.001);
    let n = 101;
    // 10 samples per segment (3.6 ms); points on a line, so the cubic is the line.
    begin(&mut bus, n, 10, 0, [0, 100, 200]);
    let drive = bus.drive(n).unwrap();
    let start = drive.stats().begun_at.unwrap() as f64 * 1e-9;
    let mut profile = Vec::new();
    for k in 0..40 {
        bus.advance(start + f64::from(k) * 0.36e-3).unwrap();
        profile.push(bus.drive(n).unwrap().profile());
    }
    // Segment 1→2 starts from rest (slope 0) and ends at 100; segment 2→3 ends at 200 with
    // the line's slope: 100 at one segment, 200 at two.
    let at_segments: Vec<f64> = profile.iter().step_by(10).copied().collect();
    assert!((at_segments[1] - 100.0).abs() < 1.0, "{at_segments:?}");
    assert!((at_segments[2] - 200.0).abs() < 1.0, "{at_segments:?}");
    // QP[4] was never written: the segment starting at QP[3] cannot fetch it, and the drive
    // stops on QP[3] with the underflow emergency.
    assert!(!bus.drive(n).unwrap().pt_running());
    assert_eq!(bus.drive(n).unwrap().profile(), 200.0);
    let emcy: Vec<DriveEmergency> = std::iter::from_fn(|| bus.try_receive())
        .filter_map(|f| match Incoming::classify(&f) {
            Incoming::Emcy { emcy, .. } => Some(DriveEmergency::decode(&emcy)),
            _ => None,
        })
        .collect();
    assert!(matches!(
        emcy.as_slice(),
        [DriveEmergency::MotionTerminated { reason: 3, .. }]
    ));
    assert_eq!(bus.drive(n).unwrap().stats().underflows, 1);
}

#[test]
fn queue_low_per_mp5_and_queue_full_on_overwrite() {
    let mut bus = VirtualBus::new(1_000_000, [whistle(0)]);
    exchange(&mut bus, &[Nmt::START_ALL.to_frame()], 0.001);
    let n = 101;
    // 50 samples per segment (18 ms); warn when fewer than 2 points are unexecuted.
    begin(&mut bus, n, 50, 2, [0, 0, 0]);
    // Write QP[4]: QP[3] and QP[4] are then unexecuted. Writing QP[4] again overwrites a
    // point not yet executed: refused with "queue full".
    let mut received = exchange(&mut bus, &[set(n, Mnemonic::QP, 4, 0)], 0.001);
    received.extend(exchange(&mut bus, &[set(n, Mnemonic::QP, 4, 0)], 0.001));
    // The next boundary fetches QP[3]: one unexecuted point left, the queue-low warning.
    bus.advance(bus.now() + 0.02).unwrap();
    received.extend(std::iter::from_fn(|| bus.try_receive()));
    let emcy: Vec<DriveEmergency> = received
        .iter()
        .filter_map(|f| match Incoming::classify(f) {
            Incoming::Emcy { emcy, .. } => Some(DriveEmergency::decode(&emcy)),
            _ => None,
        })
        .collect();
    assert!(
        emcy.contains(&DriveEmergency::QueueFull { index: 4 }),
        "{emcy:?}"
    );
    assert!(
        emcy.iter()
            .any(|e| matches!(e, DriveEmergency::QueueLow { read: 2, .. })),
        "{emcy:?}"
    );
}

#[test]
fn the_drive_limits_its_speed_and_lags_like_a_servo() {
    // A 0.2 rad step in one segment: the motor may move at most 0.9 rad/s.
    let mut bus = VirtualBus::new(1_000_000, [whistle(0)]);
    exchange(&mut bus, &[Nmt::START_ALL.to_frame()], 0.001);
    let n = 101;
    let step = (0.2 * 817_741.0 / std::f64::consts::TAU) as i32;
    begin(&mut bus, n, 10, 0, [0, step, step]);
    let mut last = bus.drive(n).unwrap().joint_position();
    let mut fastest: f64 = 0.0;
    // Over ten samples, so that the rounding of PX does not show.
    let dt = 3.6e-3;
    for _ in 0..100 {
        bus.advance(bus.now() + dt).unwrap();
        let now = bus.drive(n).unwrap().joint_position();
        fastest = fastest.max((now - last).abs() / dt);
        last = now;
    }
    assert!(fastest <= 0.9 * 1.01, "{fastest} rad/s");
    assert!(fastest > 0.85, "{fastest} rad/s");
    // It arrives (PT ended by underflow on QP[4], holding QP[3] = the step).
    assert!((last - (1.5708 + 0.2)).abs() < 2e-5, "{last}");
}

#[test]
fn injected_emergencies_go_out_at_once() {
    let mut bus = VirtualBus::new(500_000, [whistle(0)]);
    let emcy = Emcy {
        code: 0x4310,
        register: 0x09,
        manufacturer: [1, 0, 0, 0, 0],
    };
    bus.drive_mut(101)
        .unwrap()
        .inject(DriveEmergency::Other(emcy));
    bus.advance(0.001).unwrap();
    let frame = bus.try_receive().unwrap();
    assert_eq!(frame.id(), 0x0E5);
    assert_eq!(Emcy::parse(&frame).unwrap().1, emcy);
    // A silent drive sends nothing, not even emergencies.
    bus.drive_mut(101).unwrap().faults.silent = true;
    bus.drive_mut(101)
        .unwrap()
        .inject(DriveEmergency::Other(emcy));
    bus.advance(0.002).unwrap();
    assert_eq!(bus.try_receive(), None);
}
