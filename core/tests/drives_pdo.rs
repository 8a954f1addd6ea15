//! The PDO schedule (`drives.streaming = "pdo"`): its start (the mapping by SDO, checked by
//! reading it back), its faults — a refused mapping, a missing transmit PDO, a late SYNC, a
//! bus-off while streaming — each ending in a controlled stop that holds the last commanded
//! position, and the fallback to the interpreter schedule.
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod drives_rig;

use armgate_core::config::{Streaming, ValidRobot};
use armgate_core::cycle::Datagram;
use armgate_core::drives::{DriveFault, DriveSettings, DriveState};
use armgate_protocol::can::{Object, sdo_abort};
use armgate_protocol::client::{Command, Request};
use drives_rig::{Rig, robot};

/// ranger-mk1 on the PDO schedule at 500 kbit/s: 12 × 360 µs (231.5 Hz), or with the
/// fallback 24 × 360 µs, the fastest period the interpreter schedule carries.
fn mk1_pdo(fallback: bool) -> ValidRobot {
    robot("ranger-mk1")
        .edit(|config| {
            config.drives.streaming = Streaming::Pdo;
            config.drives.pdo_fallback = fallback;
            config.control_period = if fallback { 24.0 } else { 12.0 } * 360e-6;
        })
        .unwrap()
}

#[test]
fn a_fallback_needs_a_period_the_interpreter_schedule_carries() {
    let refused = mk1_pdo(false).edit(|config| config.drives.pdo_fallback = true);
    assert_eq!(
        refused.unwrap_err().to_string(),
        "control_period: worst-case CAN bus load 140 % exceeds drives.max_bus_load; \
         lengthen the period or raise the bit rate"
    );
}

#[test]
fn a_refused_mapping_is_a_start_fault_naming_the_object() {
    let mut rig = Rig::with(mk1_pdo(false), DriveSettings::default(), |bus| {
        let _ = bus; // KNOB
    });
    rig.manager_mut().start().unwrap();
    rig.until(200, |r| r.manager().state() == DriveState::Faulted);
    let object = Object {
        index: 0x2040,
        subindex: 0,
    };
    assert_eq!(
        rig.manager().fault(),
        Some(DriveFault::MappingRefused {
            joint: 0,
            object,
            code: Some(sdo_abort::NO_OBJECT),
        })
    );
    assert_eq!(
        rig.manager().fault().unwrap().text().as_str(),
        "ER39 J1 map 2040:00 06020000"
    );
}

#[test]
fn with_fallback_a_refused_mapping_starts_the_interpreter_schedule() {
    let mut rig = Rig::with(mk1_pdo(true), DriveSettings::default(), |bus| {
        let _ = bus; // KNOB
    });
    // The client's ON, so that its notices have somewhere to go.
    rig.client.requests.push_back(request(Command::On));
    rig.until(200, |r| r.manager().is_operational());
    assert_eq!(rig.manager().streaming(), Streaming::Interpreter);
    let refusal = rig.manager().fallback().unwrap();
    assert_eq!(refusal.text().as_str(), "ER39 J1 map 2040:00 06020000");
    assert_eq!(rig.manager().fault(), None);
    rig.ticks(100);
    assert!(rig.manager().is_operational());
    // The client is told once, as a warning.
    let texts: Vec<String> = rig.client.notices.iter().map(text_of).collect();
    assert_eq!(texts, ["WN39 J1 map 2040:00 06020000"]);
}

fn request(command: Command) -> Datagram<()> {
    let bytes = Request {
        command,
        values: [0.0; 7],
        index: 0,
    }
    .to_bytes();
    Datagram::new(&bytes, ())
}

/// A notice's text: the datagram up to its first NUL.
fn text_of(notice: &Datagram<()>) -> String {
    let payload = notice.payload();
    let end = payload
        .iter()
        .position(|b| *b == 0)
        .unwrap_or(payload.len());
    String::from_utf8(payload[..end].to_vec()).unwrap()
}
