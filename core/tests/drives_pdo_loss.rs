//! The PDO schedule's adaptive lead (`drives.pdo_lead_raise`): on a bus that loses frames the
//! stream raises every drive's lead together, holds it while losses continue and lowers it
//! after a quiet interval; on a clean bus it keeps the robot file's lead.
#![allow(clippy::approx_constant)] // the seed's ready pose, as it wrote it
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod drives_rig;

use armgate_core::config::{Streaming, ValidRobot};
use armgate_core::drives::DriveSettings;
use armgate_core::drives::streaming::PDO_LEAD_RAISE;
use armgate_core::motion::Mode;
use armgate_core::sim::VirtualBus;
use drives_rig::{Rig, robot};

const MK1_READY: [f64; 6] = [1.5708, 0.6, -0.4, 0.2, 1.8, 0.1];

/// ranger-mk1 on the PDO schedule at 500 kbit/s, 12 × 360 µs (231.5 Hz), at `pdo_lead`,
/// with faster joint moves than the seed's (a move takes a second or two).
fn mk1_pdo(pdo_lead: Option<u16>) -> ValidRobot {
    robot("ranger-mk1")
        .edit(|config| {
            for joint in config.joints.iter_mut() {
                joint.max_velocity = 0.4;
                joint.max_acceleration = 1.0;
                joint.max_rate = 2.0;
            }
            config.drives.streaming = Streaming::Pdo;
            config.drives.pdo_lead = pdo_lead;
            config.control_period = 12.0 * 360e-6;
        })
        .unwrap()
}

/// Every drive's reported lead is `lead` or one less (a drive whose segment boundary precedes
/// the SYNC reads one less): the drives were raised or lowered together.
fn all_at(rig: &Rig, lead: u16) -> bool {
    (0..6)
        .filter_map(|j| rig.manager().lead(j))
        .all(|l| (u32::from(lead) - 1..=u32::from(lead)).contains(&l))
}

/// A fixed-seed loss pattern of 1 % for 3 s while the arm moves, then a clean bus: the lead
/// rises on every drive together, holds while points are lost, comes down one point per quiet
/// interval, and no drive underflows. `pdo_lead = 3`: a point lost while a drive sits at its
/// least lead 2 would underflow it before any report could show the loss (docs/drives.md,
/// "The lead").
#[test]
fn the_lead_rises_on_loss_and_falls_after_quiet_on_every_drive_together() {
    let config = mk1_pdo(Some(3));
    let settings = DriveSettings {
        pdo_lead_quiet: 0.5,
        ..DriveSettings::default()
    };
    let mut rig = Rig::started(&config, &settings, VirtualBus::for_robot(&config));
    rig.ctrl_mut().set_mode(Mode::Joint).unwrap();
    rig.ctrl_mut().move_joints(&MK1_READY, 0.0).unwrap();
    rig.ticks(50);
    assert_eq!(rig.manager().pdo_lead_now(), 3);
    assert!(all_at(&rig, 3));

    rig.bus_mut().set_frame_loss(0.01, 5);
    let mut highest = 0;
    for _ in 0..700 {
        rig.tick();
        highest = highest.max(rig.manager().pdo_lead_now());
        assert!(
            rig.manager().is_operational(),
            "{:?}",
            rig.manager().fault()
        );
    }
    let stats = rig.manager().stats();
    assert!(stats.points_lost > 0, "{stats:?}");
    assert_eq!(highest, 3 + PDO_LEAD_RAISE, "{stats:?}");
    assert_eq!(u32::from(PDO_LEAD_RAISE), stats.lead_raised, "{stats:?}");
    assert_eq!(stats.lead_lowered, 0, "held while losses continue");

    rig.bus_mut().set_frame_loss(0.0, 0);
    // Settled at the raised lead: every drive there.
    rig.ticks(10);
    assert_eq!(rig.manager().pdo_lead_now(), 3 + PDO_LEAD_RAISE);
    assert!(all_at(&rig, 3 + PDO_LEAD_RAISE));
    // 0.5 s quiet = 116 cycles per point down: all of it within 4 intervals, every drive
    // following.
    let mut lowered_at = Vec::new();
    for cycle in 0..500 {
        let before = rig.manager().pdo_lead_now();
        rig.tick();
        if rig.manager().pdo_lead_now() < before {
            lowered_at.push(cycle);
        }
        if cycle > 0 && lowered_at.last() == Some(&(cycle - 5)) {
            assert!(all_at(&rig, rig.manager().pdo_lead_now()));
        }
    }
    assert_eq!(
        lowered_at.len(),
        usize::from(PDO_LEAD_RAISE),
        "{lowered_at:?}"
    );
    assert!(lowered_at.windows(2).all(|w| w[1] - w[0] >= 116));
    assert_eq!(rig.manager().pdo_lead_now(), 3);
    assert!(all_at(&rig, 3));
    assert_eq!(
        rig.manager().stats().lead_lowered,
        u32::from(PDO_LEAD_RAISE)
    );

    // Each change was one point more (or less) on every drive: the same number of points
    // reached each drive, less the ones it lost.
    rig.until(3000, |r| !r.ctrl().is_moving());
    rig.ticks(20);
    for (q, goal) in rig.drive_positions().iter().zip(MK1_READY) {
        assert!((q - goal).abs() < 1e-4, "at {q}, goal {goal}");
    }
    assert!(rig.bus().drives().all(|d| d.stats().underflows == 0));
    assert!(rig.manager().fault().is_none());
}

/// On a clean bus the lead stays the robot file's: nothing lost, nothing raised.
#[test]
fn a_clean_bus_keeps_the_robot_files_lead() {
    let config = mk1_pdo(None);
    let mut rig = Rig::started(
        &config,
        &DriveSettings::default(),
        VirtualBus::for_robot(&config),
    );
    rig.ctrl_mut().set_mode(Mode::Joint).unwrap();
    rig.ctrl_mut().move_joints(&MK1_READY, 0.0).unwrap();
    rig.until(3000, |r| !r.ctrl().is_moving());
    let stats = rig.manager().stats();
    assert_eq!(
        (stats.points_lost, stats.lead_raised, stats.lead_lowered),
        (0, 0, 0)
    );
    assert_eq!(rig.manager().pdo_lead_now(), 2);
}

/// `drives.pdo_lead_raise = 0` keeps the lead fixed, whatever is lost; the raised lead must
/// stay within 8 points.
#[test]
fn the_robot_file_bounds_or_turns_off_the_raise() {
    let config = mk1_pdo(Some(4))
        .edit(|config| config.drives.pdo_lead_raise = Some(0))
        .unwrap();
    let mut rig = Rig::started(
        &config,
        &DriveSettings::default(),
        VirtualBus::for_robot(&config),
    );
    rig.bus_mut().set_frame_loss(0.01, 5);
    rig.ticks(500);
    assert!(rig.manager().stats().points_lost > 0);
    assert_eq!(rig.manager().pdo_lead_now(), 4);
    assert_eq!(rig.manager().stats().lead_raised, 0);

    let refused = mk1_pdo(Some(6))
        .edit(|config| config.drives.pdo_lead_raise = Some(3))
        .unwrap_err()
        .to_string();
    assert!(refused.contains("drives.pdo_lead_raise"), "{refused}");
    // Without the key the default raise stops at 8.
    let config = mk1_pdo(Some(7));
    let rig = Rig::started(
        &config,
        &DriveSettings::default(),
        VirtualBus::for_robot(&config),
    );
    assert_eq!(rig.manager().pdo_lead_now(), 7);
}
