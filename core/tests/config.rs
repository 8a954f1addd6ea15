//! Robot files: every shipped file loads, round-trips through postcard, and bad files are
//! refused with an error that names the field.
#![allow(
    missing_docs,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod common;

use armgate_core::config::{
    ConfigReason, LoadError, ProfileKind, RobotConfig, ValidRobot, parse_toml,
};
use armgate_core::drives::{DriveManager, DriveSettings};

fn mk1_text() -> String {
    std::fs::read_to_string(common::robots_dir().join("ranger-mk1.toml")).unwrap()
}

fn refusal(text: &str) -> String {
    match parse_toml(text) {
        Ok(_) => panic!("accepted a bad robot file"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn every_shipped_robot_loads_and_round_trips_through_postcard() {
    let robots = common::all_robots();
    assert!(
        robots.len() >= 7,
        "robots/: {:?}",
        robots.iter().map(|r| &r.0).collect::<Vec<_>>()
    );
    for (name, config) in robots {
        assert_eq!(config.name.as_str(), name, "file name and `name` differ");
        let mut buf = [0u8; 4096];
        let bytes = postcard::to_slice(config.config(), &mut buf).unwrap();
        let back: RobotConfig = postcard::from_bytes(bytes).unwrap();
        assert_eq!(&back, config.config(), "{name}");
        assert_eq!(back.validate().unwrap(), config, "{name}");
    }
}

/// The firmware's build script refuses a robot that the drive manager would refuse at boot
/// with its default settings; every shipped robot must pass that check.
#[test]
fn every_shipped_robot_is_accepted_by_the_drive_manager() {
    for (name, config) in common::all_robots() {
        if let Err(e) = DriveManager::new(&config, &DriveSettings::default()) {
            panic!("{name}: {e}");
        }
    }
}

#[test]
fn min_above_max_names_the_joint_and_field() {
    let text = mk1_text().replacen("min = -0.785", "min = 4.0", 1);
    assert_eq!(
        refusal(&text),
        "robot file: joint 2, min: minimum is greater than maximum"
    );
}

#[test]
fn nan_names_the_field() {
    let text = mk1_text().replacen("d = 0.538", "d = nan", 1);
    assert_eq!(
        refusal(&text),
        "robot file: joint 4, d: must be a finite number (not NaN or infinite)"
    );
    let text = mk1_text().replacen("control_period = 0.01944", "control_period = inf", 1);
    assert!(refusal(&text).contains("control_period: must be a whole number"));
}

#[test]
fn control_periods_the_shells_cannot_run_are_refused() {
    // 1e30 s made armgate-sim panic converting it to a Duration; 1e-9 s busy-looped; 0.01 s
    // is no whole number of 360 µs samples (a PT segment must be); 0.72 ms is too short.
    for period in [
        "1e30", "1e-9", "0.0", "-0.01944", "nan", "0.01", "0.00072", "1.0008",
    ] {
        let text = mk1_text().replacen(
            "control_period = 0.01944",
            &format!("control_period = {period}"),
            1,
        );
        assert_eq!(
            refusal(&text),
            "robot file: control_period: must be a whole number of 360 µs drive samples \
             from 3 to 2777 (1.08 ms to 0.99972 s)",
            "{period}"
        );
    }
    // The ends of the range are accepted (one drive, so that 1.08 ms fits on the bus).
    let one_drive = common::robot("ranger-mk1").edit(|c| {
        for joint in c.joints.iter_mut().skip(1) {
            joint.drive.node_id = 0;
        }
        c.drives.can_bitrate = 1_000_000;
    });
    for samples in [3.0, 2777.0] {
        let robot = one_drive
            .clone()
            .unwrap()
            .edit(|c| c.control_period = samples * 360e-6);
        assert!(robot.is_ok(), "{samples}: {robot:?}");
    }
}

#[test]
fn home_outside_the_limits_is_refused() {
    let text = mk1_text().replacen("home = 0.0", "home = -1.0", 1);
    assert_eq!(
        refusal(&text),
        "robot file: joint 2, drive.home: home must lie within the joint's min and max"
    );
}

#[test]
fn a_drive_schedule_over_the_bus_ceiling_is_refused() {
    // Eight drives at 125 kbit/s every 19.44 ms: 4000 bits of streaming + the heartbeat in
    // 2430 bit times, 165.1 %.
    let mk2 = common::robot("ranger-mk2");
    let slow = mk2.clone().edit(|c| c.drives.can_bitrate = 125_000);
    let e = slow.unwrap_err();
    assert_eq!(e.field, "control_period");
    assert_eq!(e.reason, ConfigReason::BusOverloaded { percent: 166 });
    assert_eq!(
        e.to_string(),
        "control_period: worst-case CAN bus load 166 % exceeds drives.max_bus_load; \
         lengthen the period or raise the bit rate"
    );
    // At 500 kbit/s the same schedule takes 41.3 %: refused under a 40 % ceiling only.
    assert!(mk2.clone().edit(|c| c.drives.max_bus_load = 0.42).is_ok());
    let e = mk2
        .clone()
        .edit(|c| c.drives.max_bus_load = 0.41)
        .unwrap_err();
    assert_eq!(e.reason, ConfigReason::BusOverloaded { percent: 42 });
    // The ceiling is a fraction of the bus.
    for ceiling in [0.0, 1.5, f64::NAN] {
        let e = mk2
            .clone()
            .edit(|c| c.drives.max_bus_load = ceiling)
            .unwrap_err();
        assert_eq!(
            (e.field, e.reason),
            ("drives.max_bus_load", ConfigReason::NotAFraction)
        );
    }
    // Joints without a drive put nothing on the bus.
    let hybrid = common::robot("hybrid").edit(|c| c.drives.can_bitrate = 125_000);
    assert!(hybrid.is_ok());
}

#[test]
fn only_validation_makes_a_valid_robot() {
    // The round trip through the plain description validates again, with the same result.
    let robot = common::robot("ranger-mk1");
    let again = ValidRobot::try_from(robot.clone().into_config()).unwrap();
    assert_eq!(again, robot);
    // An edit that breaks a rule gives the error, not a robot.
    let e = robot.edit(|c| c.joints[0].max = -5.0).unwrap_err();
    assert_eq!(
        (e.joint, e.field, e.reason),
        (Some(0), "min", ConfigReason::MinAboveMax)
    );
}

#[test]
fn every_documented_field_is_read() {
    // `ik.divergence_margin` was documented and validated but never read: it is gone (the
    // controller's reach check is stricter than the seed's divergence guard it described).
    let text = mk1_text().replacen("[drives]", "[ik]\ndivergence_margin = 1e-4\n\n[drives]", 1);
    assert!(refusal(&text).contains("divergence_margin"));
}

#[test]
fn unknown_joint_type_is_refused() {
    let text = mk1_text().replacen("type = \"revolute\"", "type = \"helical\"", 1);
    let e = refusal(&text);
    assert!(
        e.contains("unknown variant `helical`") && e.contains("revolute"),
        "{e}"
    );
}

#[test]
fn wrong_joint_counts_are_refused() {
    let text = mk1_text();
    let first_joint = text.find("[[joints]]").unwrap();
    let header = &text[..first_joint];
    assert!(refusal(header).contains("joints"), "no joints");

    let joint = text[first_joint..].split("[[joints]]").nth(1).unwrap();
    let mut nine = header.to_string();
    for id in 0..9 {
        nine.push_str("[[joints]]");
        nine.push_str(&joint.replace("node_id = 101", &format!("node_id = {}", 101 + id)));
    }
    let e = refusal(&nine);
    assert!(
        e.contains("invalid length 9, expected at most 8 entries"),
        "{e}"
    );
}

#[test]
fn empty_joint_list_is_refused_by_validation() {
    let e = common::robot("ranger-mk1")
        .edit(|config| config.joints.clear())
        .unwrap_err();
    assert_eq!((e.field, e.reason), ("joints", ConfigReason::NoJoints));
}

#[test]
fn unknown_and_missing_fields_are_refused() {
    let e = refusal(&mk1_text().replacen("max_rate = 0.2", "max_rate = 0.2\nmax_snap = 1.0", 1));
    assert!(e.contains("max_snap"), "{e}");
    let e = refusal(&mk1_text().replacen("control_period = 0.01944", "", 1));
    assert!(e.contains("control_period"), "{e}");
}

#[test]
fn jerk_limited_profile_needs_every_jerk_limit() {
    let jerk_text =
        || std::fs::read_to_string(common::robots_dir().join("ranger-mk1-jerk.toml")).unwrap();
    let robot = parse_toml(&jerk_text()).unwrap();
    assert_eq!(robot.motion.profile, ProfileKind::JerkLimited);
    assert_eq!(robot.joint_jerk_limits().unwrap()[2], 5.0);
    assert_eq!(robot.cartesian_jerk_limits().unwrap()[0], 0.02);
    // The seed's file: trapezoids, no jerk limits needed or used.
    let seed = parse_toml(&mk1_text()).unwrap();
    assert_eq!(seed.motion.profile, ProfileKind::Trapezoid);
    assert_eq!(seed.joint_jerk_limits(), None);
    assert_eq!(seed.cartesian_jerk_limits(), None);
    let e = refusal(&jerk_text().replacen(
        "max_jerk = 5.0 # rad/s³: 0.1 s to full acceleration\n",
        "",
        2,
    ));
    assert_eq!(
        e,
        "robot file: joint 1, max_jerk: is required by [motion] profile = \"jerk-limited\""
    );
    let e = refusal(&jerk_text().replacen("max_jerk = [0.02,", "max_jerk = [0.0,", 1));
    assert_eq!(
        e,
        "robot file: cartesian.max_jerk: must be greater than zero"
    );
    let e = refusal(&jerk_text().replacen("max_jerk = [0.02, 0.02, 0.02, 0.1, 0.1, 0.1]", "", 1));
    assert!(
        e.starts_with("robot file: cartesian.max_jerk: is required"),
        "{e}"
    );
    // A jerk limit is checked even where the trapezoid ignores it.
    let e = refusal(&mk1_text().replacen("max_rate = 0.2", "max_rate = 0.2\nmax_jerk = -1.0", 1));
    assert_eq!(
        e,
        "robot file: joint 1, max_jerk: must be greater than zero"
    );
    let e = refusal(&jerk_text().replacen("\"jerk-limited\"", "\"s-curve\"", 1));
    assert!(e.contains("s-curve"), "{e}");
}

#[test]
fn drive_errors_name_the_field() {
    let e = refusal(&mk1_text().replacen("node_id = 102", "node_id = 101", 1));
    assert_eq!(
        e,
        "robot file: joint 2, drive.node_id: node id is used by an earlier joint"
    );
    let e = refusal(&mk1_text().replacen("counts_per_rev = 817741", "counts_per_rev = 0", 1));
    assert!(
        e.starts_with("robot file: joint 1, drive.counts_per_rev"),
        "{e}"
    );
    let e = refusal(&mk1_text().replacen("can_bitrate = 500000", "can_bitrate = 400000", 1));
    assert!(e.starts_with("robot file: drives.can_bitrate"), "{e}");
    let e = refusal(&mk1_text().replacen("node_id = 101", "node_id = 200", 1));
    assert!(e.starts_with("robot file: joint 1, drive.node_id"), "{e}");
}

#[test]
fn workspace_boxes_must_be_ordered() {
    let text = mk1_text().replacen(
        "[-0.2, 0.2, -0.2, 0.2, -0.1, 0.35]",
        "[0.2, -0.2, -0.2, 0.2, -0.1, 0.35]",
        1,
    );
    assert_eq!(
        refusal(&text),
        "robot file: workspace.boxes: minimum is greater than maximum"
    );
}

#[test]
fn syntax_errors_are_load_errors() {
    assert!(matches!(parse_toml("name = "), Err(LoadError::Syntax(_))));
}

/// A tick runs a few tracking solves: a robot file may not let each take 65,535 iterations.
#[test]
fn tracking_iterations_are_bounded() {
    for (value, accepted) in [
        (0, false),
        (1, true),
        (100, true),
        (101, false),
        (65535, false),
    ] {
        let text = mk1_text().replacen(
            "[drives]",
            &format!("[ik]\ntracking_iterations = {value}\n\n[drives]"),
            1,
        );
        match parse_toml(&text) {
            Ok(_) => assert!(accepted, "{value} accepted"),
            Err(e) => {
                assert!(!accepted, "{value} refused: {e}");
                assert!(
                    e.to_string()
                        .contains("ik.tracking_iterations: must be 1 to 100"),
                    "{e}"
                );
            }
        }
    }
}

/// How far the tick may slow a checked line down: 1 (never) to 1000 times, finite.
#[test]
fn line_slowdown_is_bounded() {
    for (value, accepted) in [
        ("0.5", false),
        ("1.0", true),
        ("100.0", true),
        ("1000.0", true),
        ("1000.5", false),
        ("nan", false),
        ("inf", false),
    ] {
        let text = mk1_text().replacen(
            "[drives]",
            &format!("[ik]\nline_slowdown = {value}\n\n[drives]"),
            1,
        );
        match parse_toml(&text) {
            Ok(robot) => {
                assert!(accepted, "{value} accepted");
                assert_eq!(robot.ik.line_slowdown, value.parse::<f64>().unwrap());
            }
            Err(e) => {
                assert!(!accepted, "{value} refused: {e}");
                assert!(
                    e.to_string()
                        .contains("ik.line_slowdown: must be 1 to 1000"),
                    "{e}"
                );
            }
        }
    }
}

/// A joint whose limits, in encoder counts, do not fit the drive's 32 bits is refused: the
/// drive manager would otherwise drop every set-point near them with only a counter.
#[test]
fn limits_beyond_the_drives_counts_are_refused() {
    let robot = common::robot("ranger-mk1");
    let e = robot.clone().edit(|c| c.joints[0].max = 1e5).unwrap_err();
    assert_eq!(
        (e.joint, e.field, e.reason),
        (
            Some(0),
            "drive.counts_per_rev",
            ConfigReason::CountsOverflow
        )
    );
    // The shipped counts fit.
    assert!(robot.edit(|_| ()).is_ok());
}

#[test]
fn revolute_limits_beyond_a_turn_are_flagged_and_no_shipped_file_has_them() {
    // Limits written in degrees (±270) load, but are flagged for the shells to warn about.
    let robot = common::robot("ranger-mk1")
        .edit(|c| {
            c.joints[3].min = -270.0;
            c.joints[3].max = 270.0;
        })
        .unwrap();
    assert_eq!(
        robot.wide_limits().collect::<Vec<_>>(),
        [(3, -270.0, 270.0)]
    );
    for name in [
        "ranger-mk1",
        "ranger-mk1-jerk",
        "ranger-mk1-table21",
        "ranger-mk2",
        "hybrid",
        "puma560",
        "ur5",
        "iiwa14",
    ] {
        assert_eq!(common::robot(name).wide_limits().count(), 0, "{name}");
    }
}

#[test]
fn joints_faster_than_their_drives_are_refused_naming_both_values() {
    // Issue 33: ur5's joints at 3.14 rad/s on drives configured for 0.9 (the default) fell
    // 4.4 rad behind their commands. Without the drives' max_speed the file is refused.
    let ur5 = std::fs::read_to_string(common::robots_dir().join("ur5.toml")).unwrap();
    let slow_drives = ur5.replace(", max_speed = 3.141592653589793 }", " }");
    assert_eq!(
        refusal(&slow_drives),
        "robot file: joint 1, max_rate: 3.142 exceeds the drive.max_speed 0.900 the drive is \
         configured for (it would fall behind its commands)"
    );
    let robot = common::robot("ranger-mk1");
    let e = robot
        .clone()
        .edit(|c| c.joints[2].drive.max_acceleration = Some(0.4))
        .unwrap_err();
    assert_eq!(
        e.to_string(),
        "joint 3, max_acceleration: 0.500 exceeds the drive.max_acceleration 0.400 the drive \
         is configured for (it would fall behind its commands)"
    );
    assert!(matches!(e.reason, ConfigReason::ExceedsDrive { .. }));
    // Exactly at the drive's values is fine, and a joint without a drive has none to exceed.
    assert!(
        robot
            .clone()
            .edit(|c| {
                c.joints[2].drive.max_acceleration = Some(0.5);
                c.joints[2].drive.max_speed = 0.2;
            })
            .is_ok()
    );
    let hybrid = common::robot("hybrid").edit(|c| c.joints[0].drive.max_speed = 0.01);
    assert!(hybrid.is_ok());
    // A following-error limit must be positive.
    let e = robot
        .edit(|c| c.joints[1].max_following_error = Some(0.0))
        .unwrap_err();
    assert_eq!(
        e.to_string(),
        "joint 2, max_following_error: must be greater than zero"
    );
}

#[test]
fn flat_exclusion_boxes_are_refused() {
    let text = mk1_text().replacen(
        "[-0.2, 0.2, -0.2, 0.2, -0.1, 0.35]",
        "[-0.2, 0.2, 0.1, 0.1, -0.1, 0.35]",
        1,
    );
    assert_eq!(
        refusal(&text),
        "robot file: workspace.boxes: a box must be thicker than zero on every axis"
    );
}
