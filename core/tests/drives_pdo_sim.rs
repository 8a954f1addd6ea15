//! The simulated Whistle's side of the PDO streaming schedule, over the virtual bus: the
//! mapping by SDO and its CiA 301 rules, SYNC → TPDO3, RPDO3 → the PT table, the emergencies,
//! the group `BG`, frame loss and clock errors.
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod drives_rig;

use armgate_core::drives::{CanBus, DriveEmergency, REASON_UNDERFLOW};
use armgate_core::sim::{BusStats, SimWhistle, VirtualBus, WhistleConfig};
use armgate_protocol::can::interpreter::{Mnemonic, Reply, Value};
use armgate_protocol::can::{
    CanFrame, Incoming, MappingRefusal, Nmt, NmtCommand, NodeId, NodeMessage, Object, PtFeedback,
    PtPoint, RPDO3_COMMUNICATION, RPDO3_MAPPING, SdoRequest, SdoResponse, SdoValue, SyncObject,
    TPDO3_COMMUNICATION, TPDO3_MAPPING, exact_bits_on_wire, group_id_step, sdo_abort,
    streaming_mapping,
};
use drives_rig::frames::{exchange, pt_ring, query, set, whistle};
use drives_rig::robot;

fn node(id: u8) -> NodeId {
    NodeId::new(id).unwrap()
}

/// The ranger-mk1 drives of joints `joints` on a bus at `bitrate`, operational.
fn bus_with(bitrate: u32, joints: std::ops::Range<usize>) -> VirtualBus {
    let mut bus = VirtualBus::new(bitrate, joints.map(whistle));
    exchange(&mut bus, &[Nmt::START_ALL.to_frame()], 0.001);
    bus
}

/// One SDO request and its response.
fn sdo(bus: &mut VirtualBus, to: u8, request: SdoRequest) -> SdoResponse {
    let answers = exchange(bus, &[request.to_frame(node(to))], 0.002);
    let [answer] = answers.as_slice() else {
        panic!("{answers:?}")
    };
    let (from, response) = SdoResponse::parse(answer).unwrap();
    assert_eq!(from, node(to));
    response
}

fn write(bus: &mut VirtualBus, to: u8, index: u16, subindex: u8, value: SdoValue) -> SdoResponse {
    let object = Object { index, subindex };
    sdo(bus, to, SdoRequest::Download { object, value })
}

fn abort(index: u16, subindex: u8, code: u32) -> SdoResponse {
    SdoResponse::Abort {
        object: Object { index, subindex },
        code,
    }
}

/// Walks the streaming mapping of `to` as the manager does: write, check, read back, check.
fn map(bus: &mut VirtualBus, to: u8) -> Result<(), (Object, MappingRefusal)> {
    for step in streaming_mapping(node(to)) {
        let written = sdo(bus, to, step.write());
        assert_eq!(written.object(), step.object);
        step.check_write(&written).map_err(|e| (step.object, e))?;
        let read = sdo(bus, to, step.read_back());
        step.check_read_back(&read).map_err(|e| (step.object, e))?;
    }
    Ok(())
}

fn point(to: u8, position: i32) -> CanFrame {
    PtPoint { position }.to_frame(node(to))
}

fn emergencies(frames: &[CanFrame]) -> Vec<DriveEmergency> {
    frames
        .iter()
        .filter_map(|f| match Incoming::classify(f) {
            Incoming::Emcy { emcy, .. } => Some(DriveEmergency::decode(&emcy)),
            _ => None,
        })
        .collect()
}

fn feedback(frames: &[CanFrame]) -> Vec<(NodeId, PtFeedback)> {
    frames
        .iter()
        .filter_map(|f| match Incoming::classify(f) {
            Incoming::Feedback { node, feedback } => Some((node, feedback)),
            _ => None,
        })
        .collect()
}

#[test]
fn the_mapping_is_written_and_read_back() {
    let mut bus = bus_with(500_000, 0..6);
    for id in 101..=106 {
        map(&mut bus, id).unwrap();
        let objects = bus.drive(id).unwrap().pdo_objects();
        assert!(objects.rpdo3.valid() && objects.tpdo3.valid());
        assert_eq!(objects.rpdo3.id(), 0x400 + u16::from(id));
        assert_eq!(objects.tpdo3.id(), 0x380 + u16::from(id));
        assert_eq!(
            (objects.rpdo3.transmission, objects.tpdo3.transmission),
            (255, 1)
        );
        assert_eq!(
            objects.tpdo3.mapped().collect::<Vec<_>>(),
            [0x6064_0020, 0x2F11_0010, 0x2F12_0010]
        );
    }
    // The interpreter objects are not in the PDO dictionary: still "no object".
    assert_eq!(
        write(&mut bus, 101, 0x1401, 1, SdoValue::U32(0x0000_0365)),
        abort(0x1401, 1, sdo_abort::NO_OBJECT)
    );
}

#[test]
fn cia_301_mapping_rules() {
    let mut bus = bus_with(500_000, 0..1);
    map(&mut bus, 101).unwrap();
    let (u8, u32) = (SdoValue::U8, SdoValue::U32);
    let ok = 0;
    let (rpdo, rpdo_map) = (RPDO3_COMMUNICATION, RPDO3_MAPPING);
    let (tpdo, tpdo_map) = (TPDO3_COMMUNICATION, TPDO3_MAPPING);
    // In order, on the mapped drive: (object, sub, value, abort code or 0 for done, why).
    let cases = [
        (
            tpdo_map,
            0,
            u8(0),
            sdo_abort::DEVICE_STATE,
            "the mapping of a valid PDO",
        ),
        (
            tpdo,
            1,
            u32(0x4000_0390),
            sdo_abort::INVALID_VALUE,
            "the id of a valid PDO",
        ),
        (tpdo, 1, u32(0xC000_03E5), ok, "disable"),
        (
            tpdo_map,
            1,
            u32(0x6064_0020),
            sdo_abort::DEVICE_STATE,
            "an entry while sub 0 = 3",
        ),
        (tpdo_map, 0, u8(0), ok, "open the mapping"),
        (
            tpdo_map,
            1,
            u32(0x6063_0020),
            sdo_abort::NO_OBJECT,
            "an unknown object",
        ),
        (
            tpdo_map,
            1,
            u32(0x2002_0020),
            sdo_abort::NOT_MAPPABLE,
            "an RPDO object",
        ),
        (
            tpdo_map,
            1,
            u32(0x6064_0010),
            sdo_abort::NOT_MAPPABLE,
            "the wrong length",
        ),
        (
            rpdo_map,
            1,
            u32(0x2002_0020),
            sdo_abort::DEVICE_STATE,
            "RPDO3 is still valid",
        ),
        (
            tpdo_map,
            9,
            u32(0x6064_0020),
            sdo_abort::NO_SUBINDEX,
            "a ninth entry",
        ),
        (tpdo_map, 1, u32(0x6064_0020), ok, "entry 1"),
        (tpdo_map, 2, u32(0x6064_0020), ok, "entry 2"),
        (tpdo_map, 3, u32(0x6064_0020), ok, "entry 3"),
        (tpdo_map, 0, u8(3), sdo_abort::PDO_TOO_LONG, "96 bits"),
        (
            tpdo,
            2,
            u8(10),
            sdo_abort::INVALID_VALUE,
            "transmission type 10",
        ),
        (
            rpdo,
            0,
            u8(2),
            sdo_abort::READ_ONLY,
            "sub 0 of a communication object",
        ),
        (tpdo, 1, u32(0xC000_0390), ok, "another id while not valid"),
    ];
    for (index, subindex, value, code, why) in cases {
        let object = Object { index, subindex };
        let expected = match code {
            0 => SdoResponse::Downloaded { object },
            code => SdoResponse::Abort { object, code },
        };
        assert_eq!(
            write(&mut bus, 101, index, subindex, value),
            expected,
            "{why}"
        );
    }
}

#[test]
fn a_drive_that_refuses_the_mapping_names_the_object() {
    let mut bus = bus_with(500_000, 0..2);
    let refused = Object {
        index: RPDO3_MAPPING,
        subindex: 1,
    };
    bus.drive_mut(102).unwrap().faults.refuse_object = Some(refused);
    map(&mut bus, 101).unwrap();
    assert_eq!(
        map(&mut bus, 102),
        Err((refused, MappingRefusal::Abort(sdo_abort::NOT_MAPPABLE)))
    );
}

#[test]
fn every_sync_brings_one_tpdo3_per_drive_sampled_at_the_sync() {
    let mut bus = bus_with(500_000, 0..6);
    for id in 101..=106 {
        map(&mut bus, id).unwrap();
    }
    // The SYNC ends after its exact length; each drive's TPDO3 is ready 50 µs later, and the
    // six go out back to back in identifier order.
    let sync = SyncObject.to_frame();
    bus.try_transmit(&sync).unwrap();
    let t0 = bus.now();
    let sync_end = t0 + f64::from(exact_bits_on_wire(&sync)) * 2e-6;
    let mut arrivals = Vec::new();
    while bus.now() < t0 + 0.005 {
        bus.advance(bus.now() + 1e-6).unwrap();
        let now = bus.now();
        arrivals.extend(std::iter::from_fn(|| bus.try_receive()).map(|f| (now, f)));
    }
    let ids: Vec<u16> = arrivals.iter().map(|(_, f)| f.id()).collect();
    assert_eq!(ids, [0x3E5, 0x3E6, 0x3E7, 0x3E8, 0x3E9, 0x3EA]);
    let first_end = sync_end + 50e-6 + f64::from(exact_bits_on_wire(&arrivals[0].1)) * 2e-6;
    assert!((arrivals[0].0 - first_end).abs() < 2e-6, "{arrivals:?}");
    for (from, report) in feedback(&arrivals.iter().map(|(_, f)| *f).collect::<Vec<_>>()) {
        let drive = bus.drive(from.get()).unwrap();
        assert_eq!(report.position, drive.position());
        // No PT set up: the write pointer MP[6] and the read index are 0.
        assert_eq!((report.head, report.tail), (0, 0));
    }
    assert!(
        bus.drives()
            .all(|d| d.stats().syncs == 1 && d.stats().tpdos_sent == 1)
    );
    // Not operational: no PDOs.
    exchange(
        &mut bus,
        &[Nmt {
            command: NmtCommand::EnterPreOperational,
            node: None,
        }
        .to_frame()],
        0.001,
    );
    assert!(feedback(&exchange(&mut bus, &[sync], 0.005)).is_empty());
}

#[test]
fn missing_tpdos_for_a_few_syncs_or_for_ever() {
    let mut bus = bus_with(1_000_000, 0..2);
    map(&mut bus, 101).unwrap();
    map(&mut bus, 102).unwrap();
    bus.drive_mut(101).unwrap().faults.skip_tpdos = 3;
    bus.drive_mut(102).unwrap().faults.skip_tpdos = u32::MAX;
    let mut from_101 = Vec::new();
    for k in 0..10 {
        let got = feedback(&exchange(&mut bus, &[SyncObject.to_frame()], 0.002));
        from_101.push(got.iter().filter(|(n, _)| n.get() == 101).count());
        assert!(got.iter().all(|(n, _)| n.get() == 101), "sync {k}: {got:?}");
    }
    assert_eq!(from_101, [0, 0, 0, 1, 1, 1, 1, 1, 1, 1]);
    assert_eq!(bus.drive(101).unwrap().stats().tpdos_skipped, 3);
    assert_eq!(bus.drive(102).unwrap().stats().tpdos_skipped, 10);
}

#[test]
fn rpdo3_points_go_to_the_write_pointer_and_tpdo3_reports_the_pointers() {
    let mut bus = bus_with(1_000_000, 0..1);
    map(&mut bus, 101).unwrap();
    // 10 samples (3.6 ms) per segment, points on a line.
    pt_ring(&mut bus, 101, 10, 0);
    for k in 0..4 {
        exchange(&mut bus, &[point(101, 100 * k)], 0.0005);
    }
    let table = bus.drive(101).unwrap().table();
    assert_eq!(
        (1..=4).map(|i| table.qp(i).unwrap()).collect::<Vec<_>>(),
        [0, 100, 200, 300]
    );
    assert_eq!(table.write_pointer(), 5);
    let report = feedback(&exchange(&mut bus, &[SyncObject.to_frame()], 0.001));
    assert_eq!((report[0].1.head, report[0].1.tail), (5, 0));
    // Begin, then one point per segment, each with a SYNC: the read pointer follows.
    exchange(&mut bus, &[set(101, Mnemonic::PT, 0, 1)], 0.001);
    let begun = exchange(&mut bus, &[query(101, Mnemonic::BG, 0)], 0.001);
    assert!(matches!(
        Reply::parse(&begun[0]).unwrap().1,
        Reply::Value {
            value: Value::Int(0),
            ..
        }
    ));
    let mut tails = Vec::new();
    for k in 4..16 {
        let frames = exchange(
            &mut bus,
            &[point(101, 100 * k), SyncObject.to_frame()],
            3.6e-3,
        );
        let got = feedback(&frames);
        tails.push(got[0].1.tail);
        assert!(emergencies(&frames).is_empty(), "{frames:?}");
    }
    // The ring wraps: QP[6] then QP[1]; every segment advances the read pointer by one.
    assert!(tails.windows(2).all(|w| w[1] == w[0] % 6 + 1), "{tails:?}");
    let drive = bus.drive(101).unwrap();
    assert!(drive.pt_running());
    assert_eq!(drive.stats().pdo_points, 16);
    // The head pointer wrapped as well: 16 points written into a ring of 6, next is QP[5].
    assert_eq!(drive.table().write_pointer(), 16 % 6 + 1);
}

#[test]
fn pdo_streaming_emergencies() {
    let mut bus = bus_with(1_000_000, 0..1);
    // RPDO3 valid with nothing mapped: "PDO not mapped".
    let u8 = SdoValue::U8;
    let u32 = SdoValue::U32;
    write(&mut bus, 101, RPDO3_COMMUNICATION, 1, u32(0xC000_0465));
    write(&mut bus, 101, RPDO3_MAPPING, 0, u8(0));
    write(&mut bus, 101, RPDO3_COMMUNICATION, 1, u32(0x4000_0465));
    let not_mapped = emergencies(&exchange(&mut bus, &[point(101, 0)], 0.001));
    assert_eq!(not_mapped, [DriveEmergency::PdoNotMapped { cob_id: 0x465 }]);

    map(&mut bus, 101).unwrap();
    // No ring yet: the write pointer is out of range.
    let out_of_range = emergencies(&exchange(&mut bus, &[point(101, 0)], 0.001));
    assert_eq!(
        out_of_range,
        [DriveEmergency::WritePointerOutOfRange { write: 0 }]
    );
    // Queue low when fewer than 3 points are unexecuted; overflow when a point would land on
    // one not yet executed.
    pt_ring(&mut bus, 101, 50, 3);
    for _ in 0..4 {
        exchange(&mut bus, &[point(101, 0)], 0.0005);
    }
    exchange(&mut bus, &[set(101, Mnemonic::PT, 0, 1)], 0.001);
    exchange(&mut bus, &[query(101, Mnemonic::BG, 0)], 0.001);
    // BG fetched QP[1..=2]; QP[3] and QP[4] wait. Four more points fill QP[5], QP[6] and the
    // fetched QP[1..=2] (within one 18 ms segment); the next would overwrite QP[3], not yet
    // executed.
    for _ in 0..4 {
        let frames = exchange(&mut bus, &[point(101, 0)], 0.0005);
        assert!(emergencies(&frames).is_empty(), "{frames:?}");
    }
    let overflow = emergencies(&exchange(&mut bus, &[point(101, 0)], 0.001));
    assert_eq!(overflow, [DriveEmergency::QueueFull { index: 3 }]);
    assert_eq!(bus.drive(101).unwrap().table().write_pointer(), 3);
    assert_eq!(bus.drive(101).unwrap().stats().overflows, 1);
    // Stop feeding: the queue runs low, then dry (motion terminated, reason 3).
    let dry = emergencies(&exchange(&mut bus, &[], 0.2));
    assert!(
        dry.iter()
            .any(|e| matches!(e, DriveEmergency::QueueLow { .. })),
        "{dry:?}"
    );
    assert!(dry.contains(&DriveEmergency::MotionTerminated {
        write: 3,
        reason: REASON_UNDERFLOW
    }));
}

/// Gives `members` the group id `group` (0x2040), then resets communication and starts
/// every drive again: the group id takes effect, and the PDOs return to their defaults.
fn join_group(bus: &mut VirtualBus, members: &[u8], group: u8) {
    let step = group_id_step(node(group));
    for &id in members {
        step.check_write(&sdo(bus, id, step.write())).unwrap();
        step.check_read_back(&sdo(bus, id, step.read_back()))
            .unwrap();
    }
    let reset = Nmt {
        command: NmtCommand::ResetCommunication,
        node: None,
    };
    exchange(bus, &[reset.to_frame(), Nmt::START_ALL.to_frame()], 0.002);
}

/// Maps `id` for streaming, sets up a ring of `samples` per segment, writes `points` points
/// (0, 1, …) by RPDO3 and arms PT motion at QP[1] for the next `BG`.
fn arm_pt(bus: &mut VirtualBus, id: u8, samples: i32, points: i32) {
    map(bus, id).unwrap();
    pt_ring(bus, id, samples, 0);
    for k in 0..points {
        exchange(bus, &[point(id, k)], 0.0005);
    }
    exchange(bus, &[set(id, Mnemonic::PT, 0, 1)], 0.001);
}

#[test]
fn a_group_bg_begins_every_drive_at_once() {
    const GROUP: u8 = 120;
    let mut bus = bus_with(500_000, 0..6);
    join_group(&mut bus, &[101, 102, 103, 104, 105, 106], GROUP);
    assert!(bus.drives().all(|d| d.group() == Some(node(GROUP))));
    for id in 101..=106 {
        arm_pt(&mut bus, id, 10, 4);
    }
    // One BG to the group: every drive answers with its own id, all begin together.
    let answers = exchange(&mut bus, &[query(GROUP, Mnemonic::BG, 0)], 0.003);
    let mut from: Vec<u16> = answers.iter().map(CanFrame::id).collect();
    from.sort_unstable();
    assert_eq!(from, [0x2E5, 0x2E6, 0x2E7, 0x2E8, 0x2E9, 0x2EA]);
    let begun: Vec<u64> = bus.drives().map(|d| d.stats().begun_at.unwrap()).collect();
    assert!(begun.iter().all(|&t| t == begun[0]), "{begun:?}");
    // They start moving at their own next sample: within one 360 µs sample of each other.
    let skew = bus.stats().start_skew_ns.unwrap();
    assert!(skew < 360_000, "{skew} ns");
    println!("group BG start skew over 6 drives: {} µs", skew / 1000);
}

#[test]
fn frame_loss_follows_its_probability_and_its_seed() {
    let run = |seed| {
        let mut bus = bus_with(1_000_000, 0..6);
        for id in 101..=106 {
            map(&mut bus, id).unwrap();
        }
        bus.reset_stats();
        bus.set_frame_loss(0.01, seed);
        let mut received = 0;
        for _ in 0..2000 {
            received += feedback(&exchange(&mut bus, &[SyncObject.to_frame()], 0.001)).len();
        }
        (
            bus.stats(),
            received,
            bus.drives().map(|d| d.stats().syncs).sum::<u32>(),
        )
    };
    let (stats, received, syncs) = run(7);
    let (syncs, received) = (u64::from(syncs), received as u64);
    // 2000 SYNCs on the wire, and a TPDO for every SYNC a drive heard; 1 % of them lost.
    assert_eq!(stats.frames, 2000 + syncs);
    let lost = stats.frames_lost as f64 / stats.frames as f64;
    assert!((0.007..0.013).contains(&lost), "{lost}");
    // A lost SYNC reaches none of the six drives; a lost TPDO does not reach the controller.
    let syncs_lost = (6 * 2000 - syncs) / 6;
    assert_eq!(stats.frames_lost, syncs_lost + (syncs - received));
    println!(
        "1 % frame loss, seed 7: {} of {} frames lost ({syncs_lost} SYNCs)",
        stats.frames_lost, stats.frames
    );
    // The same seed loses the same frames.
    assert_eq!(run(7).0, stats);
    assert_ne!(run(8).0.digest, stats.digest);
}

#[test]
fn clock_errors_make_segments_longer_or_shorter() {
    // One PT segment of 10 000 samples (3.6 s) on drives 100 ppm fast and slow: the motion
    // ends 2 × 100 ppm × 3.6 s = 720 µs apart.
    let mut bus = bus_with(1_000_000, 0..2);
    bus.drive_mut(101).unwrap().set_clock_error_ppm(100.0);
    bus.drive_mut(102).unwrap().set_clock_error_ppm(-100.0);
    const GROUP: u8 = 101;
    // Drive 102 joins drive 101's id as its group: a BG to 101 reaches both.
    join_group(&mut bus, &[102], GROUP);
    for id in [101, 102] {
        arm_pt(&mut bus, id, 10_000, 2);
    }
    exchange(&mut bus, &[query(GROUP, Mnemonic::BG, 0)], 0.001);
    let mut ended = [None, None];
    while ended.iter().any(Option::is_none) && bus.now() < 10.0 {
        bus.advance(bus.now() + 10e-6).unwrap();
        let now = bus.now();
        for frame in std::iter::from_fn(|| bus.try_receive()) {
            if let Incoming::Emcy { node, emcy } = Incoming::classify(&frame)
                && matches!(
                    DriveEmergency::decode(&emcy),
                    DriveEmergency::MotionTerminated { .. }
                )
            {
                ended[usize::from(node.get() - 101)] = Some(now);
            }
        }
    }
    let [Some(fast), Some(slow)] = ended else {
        panic!("{ended:?}")
    };
    // Both drives begin at the same BG; the sample phases differ by less than a sample.
    let difference = slow - fast;
    assert!((difference - 720e-6).abs() < 370e-6, "{difference}");
    // A spread of clock errors is drawn from the seed, within the bound.
    let mut spread = bus_with(1_000_000, 0..6);
    spread.spread_clock_errors(100.0, 1);
    let ppm: Vec<f64> = spread.drives().map(SimWhistle::clock_error_ppm).collect();
    assert!(ppm.iter().all(|p| p.abs() <= 100.0), "{ppm:?}");
    assert!(ppm.windows(2).all(|w| w[0] != w[1]), "{ppm:?}");
}

/// Streams one point per drive and cycle behind one SYNC, for `seconds`, on `robot`'s drives at
/// `bitrate` with a period of `samples` drive samples. Returns the bus statistics.
fn steady_pdo_cycle(robot_name: &str, bitrate: u32, samples: u32, seconds: f64) -> BusStats {
    let config = robot(robot_name);
    let drives = config
        .joints
        .iter()
        .filter_map(|joint| WhistleConfig::for_joint(joint).map(SimWhistle::new));
    let mut bus = VirtualBus::new(bitrate, drives);
    let ids: Vec<u8> = bus.drives().map(|d| d.node().get()).collect();
    exchange(&mut bus, &[Nmt::START_ALL.to_frame()], 0.001);
    const GROUP: u8 = 120;
    join_group(&mut bus, &ids, GROUP);
    for &id in &ids {
        arm_pt(&mut bus, id, samples as i32, 3);
    }
    // One period at most before the first point: the drives fetch QP[3] one segment after
    // `BG`, and QP[4], the first point streamed, one segment later.
    exchange(&mut bus, &[query(GROUP, Mnemonic::BG, 0)], 0.001);
    bus.reset_stats();
    let period = f64::from(samples) * 360e-6;
    let cycles = (seconds / period) as i32;
    let start = bus.now();
    let mut last_tails: Vec<u16> = Vec::new();
    for k in 0..cycles {
        let mut frames = vec![SyncObject.to_frame()];
        frames.extend(ids.iter().map(|&id| point(id, 4 + k)));
        let until_next = start + f64::from(k + 1) * period - bus.now();
        let received = exchange(&mut bus, &frames, until_next);
        assert!(emergencies(&received).is_empty(), "cycle {k}: {received:?}");
        let tails: Vec<u16> = feedback(&received).iter().map(|(_, f)| f.tail).collect();
        assert_eq!(tails.len(), ids.len(), "cycle {k}");
        if !last_tails.is_empty() {
            assert!(
                tails.iter().zip(&last_tails).all(|(t, l)| *t == l % 6 + 1),
                "cycle {k}: {last_tails:?} → {tails:?}"
            );
        }
        last_tails = tails;
    }
    assert!(
        bus.drives()
            .all(|d| d.pt_running() && d.stats().underflows == 0)
    );
    bus.stats()
}

#[test]
fn a_steady_pdo_cycle_advances_every_read_pointer_by_one() {
    // SYNC, the TPDOs and the points of every drive fit in the cycle, under 70 % of the bus
    // with worst-case stuffing: six drives in 13 samples (4.68 ms, 213.7 Hz) at 500 kbit/s
    // and 7 (2.52 ms, 396.8 Hz) at 1 Mbit/s; eight in 16 (5.76 ms) and 8 (2.88 ms).
    let cases = [
        ("ranger-mk1", 500_000, 13),
        ("ranger-mk1", 1_000_000, 7),
        ("ranger-mk2", 500_000, 16),
        ("ranger-mk2", 1_000_000, 8),
    ];
    for (robot_name, bitrate, samples) in cases {
        let stats = steady_pdo_cycle(robot_name, bitrate, samples, 5.0);
        println!(
            "{robot_name}, {} kbit/s, {:.2} ms: load {:.1} % actual, {:.1} % worst-case stuffing",
            bitrate / 1000,
            f64::from(samples) * 0.36,
            100.0 * stats.load(bitrate),
            100.0 * stats.worst_case_load(bitrate)
        );
        assert!(stats.worst_case_load(bitrate) < 0.70);
    }
}
