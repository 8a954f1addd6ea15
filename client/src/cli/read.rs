//! The reading subcommands: `status`, `pose`, `joints`, `temps`.

use std::io::Write;

use super::{Cli, CliError, joint_count};
use crate::{Client, NO_READING, Pose};

/// `armgate status`: the state (SQ 0), the stop cause and who set it (SQ 2), the holder, the
/// clients and the watchdog (SQ 3), the body's nearest gap (SQ 7) and, with --key, the
/// signing counters.
pub(super) fn status(cli: &Cli, client: &mut Client, out: &mut impl Write) -> Result<(), CliError> {
    let mut status = client.status()?;
    status.cause = client.stop_cause()?;
    status.session = client.session()?;
    writeln!(out, "{status}")?;
    if let Some(nearest) = client.nearest()? {
        writeln!(out, "nearest    {}", crate::status::nearest_text(&nearest))?;
    }
    if cli.controller.key.is_some() {
        let s = client.signing_report()?;
        writeln!(
            out,
            "signing    {} signed, {} unsigned served; dropped {} unsigned, {} truncated, \
             {} forged, {} replayed",
            s.signed,
            s.unsigned,
            s.dropped_unsigned,
            s.dropped_truncated,
            s.dropped_forged,
            s.dropped_replayed
        )?;
    }
    Ok(())
}

/// `armgate pose`.
pub(super) fn pose(client: &mut Client, out: &mut impl Write) -> Result<(), CliError> {
    print_pose(&client.pose()?, out)
}

/// `armgate joints`.
pub(super) fn joints(cli: &Cli, client: &mut Client, out: &mut impl Write) -> Result<(), CliError> {
    let n = joint_count(cli, client)?;
    let q = client.joints(n)?;
    writeln!(out, "joints (rad; m for prismatic joints)")?;
    for (k, v) in q.iter().enumerate() {
        writeln!(out, "  q{:<2} {v:>10.6}", k + 1)?;
    }
    Ok(())
}

/// `armgate temps`.
pub(super) fn temps(cli: &Cli, client: &mut Client, out: &mut impl Write) -> Result<(), CliError> {
    let n = joint_count(cli, client)?;
    let t = client.temperatures(n)?;
    writeln!(out, "drive temperatures (°C)")?;
    for (k, v) in t.iter().enumerate() {
        if *v == NO_READING {
            writeln!(out, "  T{:<2}   no reading yet", k + 1)?;
        } else {
            writeln!(out, "  T{:<2} {v:>6.1}", k + 1)?;
        }
    }
    Ok(())
}

/// Writes a pose: position, quaternion and roll/pitch/yaw (spec §2.4, with its gimbal branch).
pub fn print_pose(pose: &Pose, out: &mut impl Write) -> Result<(), CliError> {
    let [x, y, z] = pose.xyz;
    let q = pose.quaternion;
    let [roll, pitch, yaw] = pose.rpy();
    writeln!(
        out,
        "position (m)     x {x:>10.6}  y {y:>10.6}  z {z:>10.6}"
    )?;
    writeln!(
        out,
        "quaternion       x {:>10.6}  y {:>10.6}  z {:>10.6}  w {:>10.6}",
        q.x, q.y, q.z, q.w
    )?;
    writeln!(
        out,
        "RPY (rad)     roll {roll:>10.6}  pitch {pitch:>10.6}  yaw {yaw:>10.6}"
    )?;
    writeln!(
        out,
        "RPY (deg)     roll {:>10.4}  pitch {:>10.4}  yaw {:>10.4}",
        roll.to_degrees(),
        pitch.to_degrees(),
        yaw.to_degrees()
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::testing::run_with;
    use crate::fake::{FakeController, text};
    use crate::status::tests::status_reply;
    use armgate_protocol::client::{Command, Reply};

    #[test]
    fn status_prints_the_state() {
        let fake = FakeController::spawn(|d| {
            let values = if d[30] == armgate_protocol::client::NEAREST_INDEX {
                [0.0125, 5.0, 1.0, 2.0, 0.0, 0.0, 0.0]
            } else {
                [1.0, 4.0, 33.0, 8.0, 0.0, 5.0, 9.5]
            };
            vec![status_reply(d, values, "ranger-mk2")]
        });
        let (result, out) = run_with(&fake, &["status"]);
        result.unwrap();
        for line in [
            "robot      ranger-mk2 (8 joints)",
            "mode       joint (1)",
            "drives     faulted (ER33)",
            "refused    5 requests",
            "nearest    12.5 mm, link 5 to link 2 (margin 0.0 mm)",
        ] {
            assert!(out.contains(line), "{line}: {out}");
        }
        let old = FakeController::spawn(|_| vec![text("ER00 Cmd SQ not understood")]);
        let (result, _) = run_with(&old, &["status"]);
        assert!(result.unwrap_err().to_string().contains("too old"));
    }

    #[test]
    fn pose_prints_rpy() {
        let fake = FakeController::spawn(|_| {
            let mut r = Reply::null(Command::Pose);
            let q = crate::pose::tests::GOLDEN_QUATERNION;
            r.values = [
                -0.0543, 0.5242, 0.2138, q.x as f32, q.y as f32, q.z as f32, q.w as f32,
            ];
            vec![r.to_bytes().to_vec()]
        });
        let (result, out) = run_with(&fake, &["pose"]);
        result.unwrap();
        assert!(out.contains("roll  -0.0007"), "{out}");
        assert!(out.contains("pitch   1.4801"), "{out}");
        assert!(
            out.contains("yaw   1.7917") || out.contains("yaw   1.7916"),
            "{out}"
        );
        assert!(out.contains("w   0.461231"), "{out}");
    }
}
