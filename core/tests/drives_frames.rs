//! The frames the drive manager relies on, its start sequence frame by frame, unit
//! conversions, the PT flow control, fault texts and the load model.
// The seed's home angles are written as it wrote them (1.5708), not as π/2.
#![allow(clippy::approx_constant)]
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod drives_rig;

use armgate_core::config::bus_load::DEFAULT_CEILING;
use armgate_core::config::{JointType, ValidRobot};
use armgate_core::drives::streaming::{FlowError, PtStream, Query, Schedule};
use armgate_core::drives::{
    BusFault, DriveEmergency, DriveFault, DriveManager, DriveSettings, DriveState, JointUnits,
    LifecycleError, REASON_UNDERFLOW, SetupError, TxError,
};
use armgate_core::kinematics::Joints;
use armgate_protocol::can::interpreter::{Index, Mnemonic, Reply, Request, Value};
use armgate_protocol::can::{
    CanFrame, Emcy, Heartbeat, Nmt, NmtState, NodeId, NodeMessage, Object, SdoRequest, SdoResponse,
};
use armgate_protocol::client::Header;
use drives_rig::{ScriptedBus, robot};

fn node(id: u8) -> NodeId {
    NodeId::new(id).unwrap()
}

// ---------------------------------------------------------------- frames on the wire

#[test]
fn interpreter_frames_the_manager_sends() {
    let n = node(101);
    let point = Request::Set {
        command: Mnemonic::QP,
        index: Index::from(5),
        value: Value::Int(-12345),
    };
    let frame = point.to_frame(n);
    assert_eq!(frame.id(), 0x365);
    assert_eq!(frame.data(), &[b'Q', b'P', 5, 0, 0xC7, 0xCF, 0xFF, 0xFF]);
    assert_eq!(Request::parse(&frame), Ok((n, point)));
    let queries = [
        (Query::Position, *b"PX\0\0"),
        (Query::ReadIndex, *b"PT\0\0"),
        (Query::Temperature, *b"TI\x01\0"),
    ];
    for (query, bytes) in queries {
        assert_eq!(query.request().to_frame(n).data(), &bytes);
    }
    let echo = Reply::Value {
        command: Mnemonic::PT,
        index: Index::ZERO,
        value: Value::Int(4),
    };
    let frame = echo.to_frame(n);
    assert_eq!((frame.id(), frame.dlc()), (0x2E5, 8));
    assert_eq!(Reply::parse(&frame), Ok((n, echo)));
}

#[test]
fn canopen_frames_the_manager_sends() {
    assert_eq!(Nmt::START_ALL.to_frame().data(), &[0x01, 0x00]);
    let beat = Heartbeat {
        state: NmtState::Operational,
    }
    .to_frame(node(127));
    assert_eq!((beat.id(), beat.data()), (0x77F, &[0x05][..]));
    // 0x1016 sub 1 = producer 127, 300 ms: 0x007F_012C.
    let sdo = SdoRequest::consumer_heartbeat(node(127), 300).to_frame(node(101));
    assert_eq!(sdo.id(), 0x665);
    assert_eq!(
        sdo.data(),
        &[0x23, 0x16, 0x10, 0x01, 0x2C, 0x01, 0x7F, 0x00]
    );
    let ack = SdoResponse::Downloaded {
        object: Object {
            index: 0x1016,
            subindex: 1,
        },
    };
    assert_eq!(
        SdoResponse::parse(&ack.to_frame(node(101))),
        Ok((node(101), ack))
    );
}

#[test]
fn drive_emergencies_decode_and_encode() {
    let cases = [
        DriveEmergency::ErrorReset,
        DriveEmergency::DigitalHall,
        DriveEmergency::QueueLow { write: 3, read: 1 },
        DriveEmergency::QueueFull { index: 4 },
        DriveEmergency::MotionTerminated {
            write: 0,
            reason: REASON_UNDERFLOW,
        },
        DriveEmergency::MessageLost,
        DriveEmergency::WritePointerOutOfRange { write: 9 },
        DriveEmergency::PdoNotMapped { cob_id: 0x465 },
        DriveEmergency::HeartbeatLost,
        DriveEmergency::Other(Emcy {
            code: 0x2310,
            register: 0x03,
            manufacturer: [1, 2, 3, 4, 5],
        }),
    ];
    for case in cases {
        let frame = case.encode().to_frame(node(103));
        let (from, emcy) = Emcy::parse(&frame).unwrap();
        assert_eq!(from, node(103));
        assert_eq!(DriveEmergency::decode(&emcy), case);
    }
    // The seed's whitelist: bytes 80 83 81 (spec §6.7).
    let hall = CanFrame::new(0x0E5, &[0x80, 0x83, 0x81, 0, 0, 0, 0, 0]).unwrap();
    let (_, emcy) = Emcy::parse(&hall).unwrap();
    assert_eq!(DriveEmergency::decode(&emcy), DriveEmergency::DigitalHall);
    // Elmo's PT underflow: FF00, register 81, code 08, field 2 = 3.
    let underflow = DriveEmergency::MotionTerminated {
        write: 0,
        reason: REASON_UNDERFLOW,
    };
    assert_eq!(
        underflow.encode().to_frame(node(1)).data(),
        &[0x00, 0xFF, 0x81, 0x08, 0, 0, 3, 0]
    );
    // The PDO schedule's: queue low (write 5, read 3), more points than the queue holds,
    // write pointer out of range, PDO not mapped (MAN-CAN301IG Table 13-4).
    let decode = |bytes: &[u8]| {
        let (_, emcy) = Emcy::parse(&CanFrame::new(0x081, bytes).unwrap()).unwrap();
        DriveEmergency::decode(&emcy)
    };
    assert_eq!(
        decode(&[0x00, 0xFF, 0x81, 0x56, 5, 0, 3, 0]),
        DriveEmergency::QueueLow { write: 5, read: 3 }
    );
    assert_eq!(
        decode(&[0x00, 0xFF, 0x81, 0x34, 2, 0, 0, 0]),
        DriveEmergency::QueueFull { index: 2 }
    );
    assert_eq!(
        decode(&[0x00, 0xFF, 0x81, 0x5B, 70, 0, 0, 0]),
        DriveEmergency::WritePointerOutOfRange { write: 70 }
    );
    assert_eq!(
        decode(&[0x00, 0xFF, 0x81, 0x5C, 0x65, 0x04, 0, 0]),
        DriveEmergency::PdoNotMapped { cob_id: 0x465 }
    );
}

// ---------------------------------------------------------------- units

fn joint(kind: JointType, counts_per_rev: i32, home: f64) -> armgate_core::config::JointConfig {
    let mut joint = robot("ranger-mk1").joints[0].clone();
    joint.kind = kind;
    joint.drive.counts_per_rev = counts_per_rev;
    joint.drive.home = home;
    joint
}

#[test]
fn counts_round_half_away_from_zero() {
    // 2π counts per revolution: one count per radian.
    let units = JointUnits::new(&joint(JointType::Revolute, 6_283_185, 0.0)).unwrap();
    let per_rad = 6_283_185.0 / std::f64::consts::TAU;
    assert_eq!(units.counts(2.5 / per_rad), Some(3)); // floor gave 2
    assert_eq!(units.counts(-2.5 / per_rad), Some(-3)); // the seed's (int)(x+0.5) gave -2
    assert_eq!(units.counts(-2.4 / per_rad), Some(-2));
    assert_eq!(units.counts_per_second(-2.5 / per_rad), Some(-3));
    assert_eq!(units.counts(f64::NAN), None);
    assert_eq!(units.counts(1e30), None);
    // Signed counts per revolution and home (ranger-mk1 joint 3).
    let units = JointUnits::new(&joint(JointType::Revolute, -414_246, 1.5708)).unwrap();
    assert_eq!(units.counts(1.5708), Some(0));
    assert_eq!(units.counts(1.5708 + std::f64::consts::PI), Some(-207_123));
    assert!((units.position(-207_123) - (1.5708 + std::f64::consts::PI)).abs() < 1e-12);
    // Prismatic: counts per metre, no 2π.
    let units = JointUnits::new(&joint(JointType::Prismatic, 100_000, 0.1)).unwrap();
    assert_eq!(units.counts(0.35), Some(25_000));
    assert!((units.position(25_000) - 0.35).abs() < 1e-15);
    // No counts: no units.
    assert_eq!(JointUnits::new(&joint(JointType::Revolute, 0, 0.0)), None);
}

#[test]
fn recalibration_moves_home_so_the_reading_is_exact() {
    let units = JointUnits::new(&joint(JointType::Revolute, 817_741, 1.5708)).unwrap();
    let moved = units.recalibrated(123_456, 0.25);
    assert_eq!(moved.position(123_456), 0.25);
    assert_eq!(moved.counts(0.25), Some(123_456));
}

// ---------------------------------------------------------------- PT flow control

#[test]
fn pt_stream_paces_by_the_read_index() {
    let mut stream = PtStream::new(6, 1000);
    // Points 4, 5, 6 go to slots 4, 5, 6.
    for (expected, value) in [(4, 1001), (5, 1002), (6, 1003)] {
        let points = stream.points(value);
        assert_eq!(points.as_slice(), &[(Index::from(expected), value)]);
    }
    // Point 6 written while the drive reads slot 4: lead 2, on target.
    stream.asked();
    stream.read_index(4).unwrap();
    assert_eq!(stream.lead(), Some(2));
    assert_eq!(stream.points(1004).len(), 1); // point 7, slot 1
    // The drive is a segment behind (slot 4 still): lead 3, the next point is skipped.
    stream.asked();
    stream.read_index(4).unwrap();
    assert_eq!(stream.lead(), Some(3));
    assert!(stream.points(1005).is_empty());
    assert_eq!(stream.points(1006).as_slice(), &[(Index::from(2), 1006)]);
    // The drive is ahead (slot 1 while point 8 is newest): lead 1, a midpoint is inserted.
    stream.asked();
    stream.read_index(1).unwrap();
    assert_eq!(stream.lead(), Some(1));
    assert_eq!(
        stream.points(1010).as_slice(),
        &[(Index::from(3), 1008), (Index::from(4), 1010)]
    );
    // Lost streams.
    stream.asked();
    assert_eq!(stream.read_index(4), Err(FlowError::Underflow)); // lead 0
    stream.asked();
    assert_eq!(stream.read_index(7), Err(FlowError::Overrun)); // not a slot
    // An answer nobody asked for changes nothing.
    assert_eq!(stream.read_index(1), Ok(()));
}

#[test]
fn pt_stream_flags_a_stalled_drive() {
    let mut stream = PtStream::new(6, 0);
    stream.points(1); // point 4, slot 4
    stream.points(2); // point 5, slot 5
    stream.asked();
    // The drive still at slot 1: lead 4.
    assert_eq!(stream.read_index(1), Err(FlowError::Overrun));
}

#[test]
fn schedule_staggers_reads_over_drives() {
    let schedule = Schedule::default();
    // While settling every drive reads its index every other cycle.
    assert!((0..6).all(|d| schedule.query(2, d, true) == Query::ReadIndex));
    assert!((0..6).all(|d| schedule.query(3, d, true) == Query::Position));
    // Afterwards each drive reads it once per 6 cycles, and each cycle one drive in six does.
    for cycle in 100..106 {
        let reads = (0..6)
            .filter(|&d| schedule.query(cycle, d, true) == Query::ReadIndex)
            .count();
        assert!(reads <= 1);
    }
    let per_drive = (200..800)
        .filter(|&c| schedule.query(c, 2, true) == Query::ReadIndex)
        .count();
    assert!((95..=100).contains(&per_drive), "{per_drive}");
    let temps = (200..800)
        .filter(|&c| schedule.query(c, 2, true) == Query::Temperature)
        .count();
    assert_eq!(temps, 6);
    // Without pacing, never the read index.
    assert!((0..600).all(|c| schedule.query(c, 1, false) != Query::ReadIndex));
}

// ---------------------------------------------------------------- fault texts

#[test]
fn fault_codes_and_texts() {
    let emcy = Emcy {
        code: 0xFF00,
        register: 0x81,
        manufacturer: [0x09, 0, 0, 0, 0],
    };
    let cases = [
        (
            DriveFault::NotAnswering { joint: 2 },
            "ER30 J3 drive not answering",
        ),
        (
            DriveFault::ErrorReply {
                joint: 1,
                command: Mnemonic::QP,
                code: 21,
            },
            "ER31 J2 QP error code 21",
        ),
        (
            DriveFault::Emergency { joint: 0, emcy },
            "ER32 J1 EMCY FF00 09",
        ),
        (
            DriveFault::Underflow { joint: 3 },
            "ER33 J4 PT buffer underflow",
        ),
        (
            DriveFault::Overrun { joint: 3 },
            "ER34 J4 PT buffer overrun",
        ),
        (DriveFault::Bus(BusFault::BusOff), "ER35 CAN bus off"),
        (
            DriveFault::Bus(BusFault::QueueFull),
            "ER35 CAN send queue full",
        ),
        (
            DriveFault::HeartbeatLost { joint: 1 },
            "ER36 J2 lost ctrl heartbeat",
        ),
        (
            DriveFault::WrongUnitMode { joint: 0, found: 2 },
            "ER37 J1 unit mode 2 not 5",
        ),
        (
            DriveFault::BeginRefused { joint: 4, value: 7 },
            "ER38 J5 did not begin (7)",
        ),
        (
            DriveFault::SdoAbort {
                joint: 0,
                code: 0x0609_0011,
            },
            "ER39 J1 SDO abort 06090011",
        ),
    ];
    for (fault, text) in cases {
        assert_eq!(fault.text().as_str(), text);
        assert!(text.len() <= 30);
        // Clients know a drive fault by its code alone (protocol's grammar).
        let written = fault.text();
        let header = Header::parse(&written).unwrap();
        assert!(header.is_drive_fault() && header.ends_motion(), "{text}");
    }
    // The widest joint number still fits.
    assert_eq!(
        DriveFault::HeartbeatLost { joint: 7 }.text().as_str(),
        "ER36 J8 lost ctrl heartbeat"
    );
}

// ---------------------------------------------------------------- load model

#[test]
fn load_model_counts_worst_case_frames() {
    let config = robot("ranger-mk1");
    let model = DriveSettings::default().load_model(&config);
    assert_eq!(model.drives, 6);
    // QP 135 + echo 135 + query 95 + answer 135.
    assert_eq!(model.bits_per_drive(), 500);
    assert_eq!(model.heartbeat_bits(), 65);
    // At the seed's 51 Hz on 500 kbit/s: 3000 bits + 65 × 0.1944 per cycle.
    let load = model.load(0.01944, 500_000);
    assert!((load - (3000.0 + 65.0 * 0.1944) / (0.01944 * 500_000.0)).abs() < 1e-12);
    let fast = model.fastest_period(500_000, DEFAULT_CEILING).unwrap();
    assert_eq!(fast.samples, 24); // 8.64 ms, 115.7 Hz
    assert!(fast.load <= 0.7 && model.load(23.0 * 360e-6, 500_000) > 0.7);
    let fast = model.fastest_period(1_000_000, DEFAULT_CEILING).unwrap();
    assert_eq!(fast.samples, 12); // 4.32 ms, 231.5 Hz
    // Eight drives (ranger-mk2) need longer periods.
    let mk2 = DriveSettings::default().load_model(&robot("ranger-mk2"));
    assert_eq!(
        mk2.fastest_period(500_000, DEFAULT_CEILING)
            .unwrap()
            .samples,
        32
    );
    assert_eq!(
        mk2.fastest_period(1_000_000, DEFAULT_CEILING)
            .unwrap()
            .samples,
        16
    );
    // Joints without a drive cost nothing.
    let hybrid = DriveSettings::default().load_model(&robot("hybrid"));
    assert_eq!(hybrid.bits_per_cycle(0.01), 0.0);
}

// ---------------------------------------------------------------- manager set-up

#[test]
fn setup_refuses_what_it_cannot_run() {
    let settings = DriveSettings::default();
    let config = robot("ranger-mk1")
        .edit(|config| config.drives.unit_mode = 2)
        .unwrap();
    assert_eq!(
        DriveManager::new(&config, &settings).err(),
        Some(SetupError::UnsupportedUnitMode(2))
    );
    // The robot file refuses periods the drives cannot run; a heartbeat far faster than the
    // one validation assumed overloads the bus.
    let eight_drives = robot("ranger-mk2");
    let chatty = DriveSettings {
        heartbeat_period: 1e-4,
        heartbeat_timeout: 0.3,
        ..settings
    };
    assert_eq!(
        DriveManager::new(&eight_drives, &chatty).err(),
        Some(SetupError::BusOverloaded)
    );
    let config = robot("ranger-mk1");
    let bad = [
        DriveSettings {
            ring_len: 5,
            ..settings
        },
        DriveSettings {
            heartbeat_timeout: 0.05,
            ..settings
        },
        DriveSettings {
            controller_node: 101,
            ..settings
        },
        DriveSettings {
            controller_node: 0,
            ..settings
        },
        DriveSettings {
            reply_timeout: f64::NAN,
            ..settings
        },
    ];
    let expected = [
        SetupError::RingSize,
        SetupError::Heartbeat,
        SetupError::ControllerNode,
        SetupError::ControllerNode,
        SetupError::BadTiming,
    ];
    for (settings, error) in bad.iter().zip(expected) {
        assert_eq!(DriveManager::new(&config, settings).err(), Some(error));
    }
}

// ---------------------------------------------------------------- the start, frame by frame

/// ranger-mk1 with a drive on joint 1 only.
fn one_drive() -> ValidRobot {
    robot("ranger-mk1")
        .edit(|config| {
            for joint in config.joints.iter_mut().skip(1) {
                joint.drive.node_id = 0;
            }
        })
        .unwrap()
}

fn answer(command: Mnemonic, index: u8, value: i32) -> CanFrame {
    Reply::Value {
        command,
        index: Index::from(index),
        value: Value::Int(value),
    }
    .to_frame(node(101))
}

/// The interpreter requests in `frames`, as (command, index, value).
fn requests(frames: &[CanFrame]) -> Vec<(Mnemonic, u16, Option<i32>)> {
    frames
        .iter()
        .filter_map(|f| Request::parse(f).ok())
        .map(|(_, r)| match r {
            Request::Query { command, index } => (command, index.get(), None),
            Request::Set {
                command,
                index,
                value: Value::Int(v),
            } => (command, index.get(), Some(v)),
            Request::Set { command, index, .. } => (command, index.get(), None),
        })
        .collect()
}

/// Answers every interpreter request in `frames` as a drive would (queries with `values`).
fn echo(bus: &mut ScriptedBus, frames: &[CanFrame], values: &dyn Fn(Mnemonic) -> i32) {
    for (command, index, value) in requests(frames) {
        let v = value.unwrap_or_else(|| values(command));
        bus.inbox.push_back(answer(command, index as u8, v));
    }
}

#[test]
fn start_sequence_frame_by_frame() {
    let config = one_drive();
    let mut manager = DriveManager::new(&config, &DriveSettings::default()).unwrap();
    let mut bus = ScriptedBus::default();
    // Idle: nothing on the bus, not even a heartbeat.
    manager.cycle(0.0, None, &mut bus);
    assert!(bus.take().is_empty());
    assert_eq!(manager.stop(), Err(LifecycleError::NotRunning));
    manager.start().unwrap();
    assert_eq!(manager.start(), Err(LifecycleError::Running));
    assert_eq!(manager.state(), DriveState::Starting);
    // Cycle 1: the NMT start and the heartbeat (last in every cycle).
    let period = config.control_period;
    let mut now = period;
    manager.cycle(now, None, &mut bus);
    let sent = bus.take();
    assert_eq!(sent.len(), 2);
    assert_eq!(sent[0], Nmt::START_ALL.to_frame());
    assert_eq!((sent[1].id(), sent[1].data()), (0x77F, &[5][..]));
    // Cycle 2: the 12 ms settle is one 19.44 ms cycle; cycle 3: the heartbeat SDO.
    now += period;
    manager.cycle(now, None, &mut bus);
    assert!(bus.take().is_empty());
    now += period;
    manager.cycle(now, None, &mut bus);
    let sent = bus.take();
    assert_eq!(
        sent,
        [SdoRequest::consumer_heartbeat(node(127), 300).to_frame(node(101))]
    );
    // Unanswered, the step waits; an SDO from a node the manager does not know is ignored and
    // does not stop the processing of what follows (the seed aborted, spec §9 item 33).
    let stranger = SdoResponse::Downloaded {
        object: Object {
            index: 0x1016,
            subindex: 1,
        },
    };
    bus.inbox.push_back(stranger.to_frame(node(55)));
    bus.inbox.push_back(stranger.to_frame(node(101)));
    // A one-byte interpreter answer (TPDO2) from the drive: malformed, not of no interest.
    bus.inbox
        .push_back(CanFrame::new(0x280 + 101, &[0x50]).unwrap());
    // The drive answers UM = 2 (speed): motor off, position mode, settle, check, motor on.
    let mut log = Vec::new();
    let mut unit_mode = 2;
    for _ in 0..40 {
        now += period;
        manager.cycle(now, None, &mut bus);
        let sent = bus.take();
        let reqs = requests(&sent);
        assert!(reqs.len() <= 2, "more than two frames in a cycle: {reqs:?}");
        if reqs.iter().any(|r| r.0 == Mnemonic::UM && r.2 == Some(5)) {
            unit_mode = 5;
        }
        let um = unit_mode;
        echo(&mut bus, &sent, &|c| match c {
            Mnemonic::UM => um,
            Mnemonic::PX => -4242,
            _ => 0,
        });
        log.push(reqs);
        if manager.state() == DriveState::Operational {
            break;
        }
    }
    assert_eq!(manager.stats().frames_ignored, 1);
    assert_eq!(manager.stats().frames_malformed, 1);
    let flat: Vec<_> = log.iter().flatten().copied().collect();
    let expected = [
        (Mnemonic::UM, 0, None),
        (Mnemonic::MO, 0, Some(0)),
        (Mnemonic::UM, 0, Some(5)),
        // … the settle cycles send nothing …
        (Mnemonic::UM, 0, None),
        (Mnemonic::MO, 0, Some(1)),
        (Mnemonic::PX, 0, None),
        (Mnemonic::MP, 1, Some(1)),
        (Mnemonic::MP, 2, Some(6)),
        (Mnemonic::MP, 3, Some(1)),
        (Mnemonic::MP, 4, Some(54)),
        (Mnemonic::MP, 5, Some(0)),
        (Mnemonic::QP, 1, Some(-4242)),
        (Mnemonic::QP, 2, Some(-4242)),
        (Mnemonic::QP, 3, Some(-4242)),
        (Mnemonic::PT, 0, Some(1)),
        (Mnemonic::BG, 0, None),
    ];
    assert_eq!(flat, expected);
    // The settle after the unit-mode change: 100 ms = 6 cycles of 19.44 ms without frames.
    let change = log
        .iter()
        .position(|r| r.iter().any(|x| x.2 == Some(5)))
        .unwrap();
    let check = log
        .iter()
        .skip(change + 1)
        .position(|r| !r.is_empty())
        .unwrap();
    assert!(check as f64 * period >= 0.1, "settled only {check} cycles");
    assert!(manager.is_operational());
    // Streaming: point 4 goes to QP[4], then a read-index query.
    now += period;
    let q = Joints::from_slice(&[1.5708 + 0.001, 0.0, 1.5708, 0.0, 1.5708, 0.0]).unwrap();
    manager.cycle(now, Some(&q), &mut bus);
    let reqs = requests(&bus.take());
    let counts = (0.001 * 817_741.0 / std::f64::consts::TAU).round() as i32;
    assert_eq!(
        reqs,
        [(Mnemonic::QP, 4, Some(counts)), (Mnemonic::PT, 0, None)]
    );
    // The measurement: PX = -4242 read at the start; the pretend joints mirror the command.
    let measured = manager.measured();
    assert!((measured[0] - (1.5708 - 4242.0 / 817_741.0 * std::f64::consts::TAU)).abs() < 1e-12);
    assert_eq!(&measured[1..], &q[1..]);
}

#[test]
fn begin_refused_and_sdo_abort_are_faults() {
    // Drive the start to BG, then answer BG with 7.
    let config = one_drive();
    let mut manager = DriveManager::new(&config, &DriveSettings::default()).unwrap();
    let mut bus = ScriptedBus::default();
    manager.start().unwrap();
    let mut now = 0.0;
    for _ in 0..40 {
        now += config.control_period;
        manager.cycle(now, None, &mut bus);
        let sent = bus.take();
        for frame in &sent {
            if let Ok((_, SdoRequest::Download { object, .. })) = SdoRequest::parse(frame) {
                bus.inbox
                    .push_back(SdoResponse::Downloaded { object }.to_frame(node(101)));
            }
        }
        echo(&mut bus, &sent, &|c| match c {
            Mnemonic::UM => 5,
            Mnemonic::BG => 7,
            _ => 100,
        });
        if manager.fault().is_some() {
            break;
        }
    }
    assert_eq!(
        manager.fault(),
        Some(DriveFault::BeginRefused { joint: 0, value: 7 })
    );
    assert!(!manager.is_operational());

    // A drive refusing the heartbeat configuration.
    let mut manager = DriveManager::new(&config, &DriveSettings::default()).unwrap();
    let mut bus = ScriptedBus::default();
    manager.start().unwrap();
    for _ in 0..3 {
        now += config.control_period;
        manager.cycle(now, None, &mut bus);
    }
    let object = Object {
        index: 0x1016,
        subindex: 1,
    };
    let abort = SdoResponse::Abort {
        object,
        code: 0x0609_0011,
    };
    bus.inbox.push_back(abort.to_frame(node(101)));
    manager.cycle(now + config.control_period, None, &mut bus);
    assert_eq!(
        manager.fault(),
        Some(DriveFault::SdoAbort {
            joint: 0,
            code: 0x0609_0011
        })
    );
    assert_eq!(manager.state(), DriveState::Stopping);
}

#[test]
fn a_full_transmit_queue_and_bus_off_are_bus_faults() {
    let config = one_drive();
    let mut manager = DriveManager::new(&config, &DriveSettings::default()).unwrap();
    let mut bus = ScriptedBus {
        refuse: Some(TxError::QueueFull),
        ..ScriptedBus::default()
    };
    manager.start().unwrap();
    manager.cycle(0.02, None, &mut bus);
    assert_eq!(manager.fault(), Some(DriveFault::Bus(BusFault::QueueFull)));
    assert_eq!(manager.state(), DriveState::Faulted);
    // A new start clears the fault; bus-off faults it again at once.
    manager.start().unwrap();
    assert_eq!(manager.fault(), None);
    let mut bus = ScriptedBus {
        bus_off: true,
        ..ScriptedBus::default()
    };
    manager.cycle(0.04, None, &mut bus);
    assert_eq!(manager.fault(), Some(DriveFault::Bus(BusFault::BusOff)));
    assert_eq!(manager.state(), DriveState::Faulted);
}

#[test]
fn a_drive_that_never_answers_is_faulted_within_the_timeout() {
    let config = one_drive();
    let mut manager = DriveManager::new(&config, &DriveSettings::default()).unwrap();
    let mut bus = ScriptedBus::default();
    manager.start().unwrap();
    let mut cycles = 0;
    while manager.fault().is_none() && cycles < 50 {
        cycles += 1;
        manager.cycle(f64::from(cycles) * config.control_period, None, &mut bus);
    }
    assert_eq!(manager.fault(), Some(DriveFault::NotAnswering { joint: 0 }));
    // NMT, settle, SDO sent in cycle 3; 50 ms is three 19.44 ms cycles: the request goes
    // again every three cycles, five times, and the fault follows more than three cycles after
    // the last repeat.
    assert_eq!(cycles, 3 + 5 * 3 + 4);
}
