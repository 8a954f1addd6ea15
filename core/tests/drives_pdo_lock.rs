//! The PDO schedule's Time Stamps (`drives.time_stamp_every`): SYNC and Time Stamp pairs lock
//! the drives' motion clocks to the controller's, so that their PT segments stop drifting
//! against the control cycle: no clock slip to correct, and every point reached under two
//! set-points after its write, whatever the drives' clock errors and sample phases.
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod drives_rig;

use armgate_core::config::{Streaming, ValidRobot};
use armgate_core::drives::DriveSettings;
use armgate_core::sim::{SimWhistle, VirtualBus, WhistleConfig};
use armgate_protocol::can::{SYNC_ID, TIME_STAMP_ID, TimeStamp};
use drives_rig::{Rig, robot};

/// ranger-mk1 on the PDO schedule at 231.5 Hz (500 kbit/s), Time Stamps as `every` says
/// (`None`: the default).
fn mk1(every: Option<u16>) -> ValidRobot {
    robot("ranger-mk1")
        .edit(|config| {
            config.drives.streaming = Streaming::Pdo;
            config.control_period = 12.0 * 360e-6;
            config.drives.time_stamp_every = every;
        })
        .unwrap()
}

/// The drives' write → reached latency, in set-points at most.
fn latency(rig: &Rig) -> f64 {
    rig.bus()
        .drives()
        .map(|d| d.stats().latency.max_ns as f64 * 1e-9 / rig.period)
        .fold(0.0, f64::max)
}

#[test]
fn a_time_stamp_follows_every_second_sync_with_the_controllers_clock() {
    let mut rig = Rig::running(&mk1(None));
    let mut stamps = Vec::new();
    for _ in 0..6 {
        rig.tick();
        let sent = rig.sent();
        assert_eq!(sent[0].id(), SYNC_ID);
        let stamp = sent.iter().position(|f| f.id() == TIME_STAMP_ID);
        if let Some(at) = stamp {
            // After the SYNC it refers to and after every point, with the tick's time.
            let last_point = sent.iter().rposition(|f| f.id() & 0x780 == 0x400).unwrap();
            assert!(at > last_point, "{sent:?}");
            let micros = TimeStamp::parse(&sent[at]).unwrap().micros;
            assert_eq!(micros, (rig.now * 1e6).round() as u32);
            stamps.push(micros);
        }
    }
    assert_eq!(stamps.len(), 3);
    let period_us = (rig.period * 1e6).round() as u32;
    assert!(stamps.windows(2).all(|w| w[1] - w[0] == 2 * period_us));
    for drive in rig.bus().drives() {
        assert!(drive.motion_clock().pairs().0 > 10);
    }
    // None with `time_stamp_every = 0`.
    let mut off = Rig::running(&mk1(Some(0)));
    off.ticks(4);
    assert!(off.sent().iter().all(|f| f.id() != TIME_STAMP_ID));
}

/// A drive 500 ppm fast gains a segment on the control cycle every 4.3 s at 231.5 Hz: without
/// Time Stamps the stream inserts points for it; with them its clock is locked and nothing
/// slips.
#[test]
fn a_fast_drive_slips_without_time_stamps_and_is_locked_with_them() {
    for (every, slips) in [(Some(0), true), (None, false)] {
        let config = mk1(every);
        let mut bus = VirtualBus::for_robot(&config);
        bus.drive_mut(103).unwrap().set_clock_error_ppm(500.0);
        let mut rig = Rig::started(&config, &DriveSettings::default(), bus);
        rig.shuttle(20.0);
        let stats = rig.manager().stats();
        assert_eq!(stats.points_inserted > 0, slips, "{every:?}: {stats:?}");
        assert!(rig.bus().drives().all(|d| d.stats().underflows == 0));
        if !slips {
            assert_eq!(stats.points_skipped, 0);
            let clock = rig.bus().drive(103).unwrap().motion_clock();
            assert!((clock.correction_ppm() + 500.0).abs() < 5.0, "{clock:?}");
            assert!(latency(&rig) < 2.0, "{} set-points", latency(&rig));
        }
    }
}

/// Drives with clocks spread over ±100 ppm and sample phases drawn at random (eight draws):
/// locked, they stream at the least lead with no slip, and every point is reached at most two
/// set-points after its write: 24 of the drive's samples, exactly that when a drive's point
/// lands in the very sample of its segment boundary in some cycles and one sample later in
/// others (the stuffing of the frames before it), else fewer.
#[test]
fn locked_drives_reach_every_point_under_two_set_points_whatever_their_phase() {
    let config = mk1(None);
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    let mut random = move || {
        // xorshift64
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    for draw in 0..8 {
        let drives = config.joints.iter().filter_map(|joint| {
            let mut whistle = WhistleConfig::for_joint(joint)?;
            whistle.sample_phase = random() * 360e-6;
            Some(SimWhistle::new(whistle))
        });
        let mut bus = VirtualBus::new(config.drives.can_bitrate, drives.collect::<Vec<_>>());
        bus.spread_clock_errors(100.0, draw);
        let mut rig = Rig::started(&config, &DriveSettings::default(), bus);
        rig.shuttle(15.0);
        let stats = rig.manager().stats();
        assert_eq!(
            (stats.points_skipped, stats.points_inserted),
            (0, 0),
            "draw {draw}"
        );
        assert!(rig.bus().drives().all(|d| d.stats().underflows == 0));
        // Two set-points of the drive's clock: of the controller's, give or take the lock's
        // residual rate error.
        assert!(
            latency(&rig) <= 2.0 * (1.0 + 1e-4),
            "draw {draw}: {}",
            latency(&rig)
        );
        for drive in rig.bus().drives() {
            let off = drive.motion_clock().correction_ppm() + drive.clock_error_ppm();
            assert!(off.abs() < 3.0, "draw {draw}: {off} ppm left");
        }
    }
}
