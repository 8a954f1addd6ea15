//! What to do about a refusal: from the reason in the refusal's text (`ER20 Cmd BG drives off`,
//! docs/protocol.md), else from the controller's state (`SQ`), else a list of what the command
//! needs (a controller that gives neither).
//!
//! The reason and the state cannot guess wrong: with the drives off or faulted no motion
//! starts whatever the mode, so the hint is `armgate on`; while they start, waiting is.

use crate::status::{DriveStatus, Motion, Name, Status};
use crate::{Mode, Text, matching};

/// The commands that start or load a Cartesian motion, and those of joint mode.
const CARTESIAN: [&str; 4] = ["BG", "VE", "GT", "GL"];
const JOINT: [&str; 3] = ["jB", "jE", "jG"];

/// The two command characters a refusal names (`ER20 Cmd BG rejected: …` → `BG`).
fn named_command(text: &str) -> Option<&str> {
    text.get(5..)?.strip_prefix("Cmd ")?.get(..2)
}

/// A hint for a refusal, if there is one to give.
pub fn hint(text: &Text, status: Option<&Status>) -> Option<String> {
    let code = matching::code(text)?;
    let s = text.as_str();
    let command = named_command(s).unwrap_or_default();
    if let Some(h) = reason_hint(code, &s.to_ascii_lowercase()) {
        return Some(h);
    }
    if let Some(status) = status {
        if let Some(h) = drive_hint(status, code) {
            return Some(h);
        }
        if code == 20 {
            return state_hint(command, status);
        }
        return None;
    }
    text_hint(code, command, &s.to_ascii_lowercase())
}

/// The hint when the drives are the reason (any refusal but ON's and OF's own).
fn drive_hint(status: &Status, code: u8) -> Option<String> {
    match (status.drives, code) {
        (DriveStatus::Running, _) | (_, 10 | 11) => None,
        (DriveStatus::Off, _) => Some("the drives are off: start them with `armgate on`".into()),
        (DriveStatus::Faulted, _) => Some(format!(
            "the drives stopped on a fault ({}): `armgate on` clears it and restarts them",
            status.drives_text()
        )),
        (DriveStatus::Starting, _) => {
            Some("the drives are still starting: try again in a moment (`armgate on` waits)".into())
        }
        (DriveStatus::Stopping, _) => {
            Some("the drives are stopping: `armgate on` restarts them".into())
        }
    }
}

/// The hint for `ER20` with the drives running: the mode, a running motion, a missing goal.
fn state_hint(command: &str, status: &Status) -> Option<String> {
    let needs = |mode: Mode| {
        (status.mode != mode).then(|| {
            format!(
                "{command} needs mode {0}, the mode is {1}: `armgate mode {0}`",
                mode.name(),
                status.mode.name()
            )
        })
    };
    let busy = || {
        (status.motion != Motion::Holding).then(|| {
            format!(
                "a {} is running: wait for it or `armgate stop`",
                status.motion.name()
            )
        })
    };
    if CARTESIAN.contains(&command) {
        needs(Mode::Cartesian)
            .or_else(busy)
            .or_else(|| Some("no goal or via point 0 stored (GT / VP 0 first)".into()))
    } else if JOINT.contains(&command) {
        needs(Mode::Joint)
            .or_else(busy)
            .or_else(|| Some("no joint goal or via point 0 stored (jG / jV 0 first)".into()))
    } else if command == "RC" {
        needs(Mode::Off).or_else(busy)
    } else {
        busy()
    }
}

/// The hint for a reason the refusal's text gives (the `ER20` reasons of docs/protocol.md).
fn reason_hint(code: u8, reason: &str) -> Option<String> {
    if code != 20 {
        return None;
    }
    if reason.ends_with("drives off")
        || reason.contains("drive fault")
        || reason.ends_with("drives stopping")
    {
        return Some("start the drives with `armgate on` (it also clears a fault)".into());
    }
    if reason.ends_with("drives starting") {
        return Some(
            "the drives are still starting: try again in a moment (`armgate on` waits for them)"
                .into(),
        );
    }
    if reason.ends_with("drives settling") {
        return Some("the drives still follow the last set-points: try again in a moment".into());
    }
    if let Some(mode) = reason
        .split_once("needs mode ")
        .and_then(|(_, m)| m.trim().parse::<f32>().ok())
        .and_then(Mode::from_value)
    {
        return Some(format!(
            "switch the mode first: `armgate mode {}`",
            mode.name()
        ));
    }
    if reason.ends_with("busy") {
        return Some("a motion is running: wait for it or `armgate stop`".into());
    }
    if reason.ends_with("no goal") {
        return Some(
            "store a goal first (`armgate send GT ...` / jG), or use `armgate move` / `jmove`"
                .into(),
        );
    }
    if reason.ends_with("no via point 0") {
        return Some("store via point 0 first (VP / jV), or use `armgate run`".into());
    }
    None
}

/// The hint from the refusal alone (a controller without reasons and without `SQ`).
fn text_hint(code: u8, command: &str, reason: &str) -> Option<String> {
    if code != 20 {
        return None;
    }
    let mode = if CARTESIAN.contains(&command) {
        "Cartesian mode (`armgate mode cart`)"
    } else if JOINT.contains(&command) {
        "joint mode (`armgate mode joint`)"
    } else if command == "RC" {
        "mode off (`armgate mode off`)"
    } else {
        return None;
    };
    if !reason.ends_with("rejected") {
        return None;
    }
    Some(format!(
        "needs {mode}, running drives (`armgate on`), a goal, and no motion running (`armgate stop`)"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fake::parsed_text;

    fn status(mode: Mode, drives: DriveStatus, fault: u8, motion: Motion) -> Status {
        Status {
            mode,
            drives,
            fault,
            joints: 6,
            motion,
            refused: 1,
            uptime: 3.0,
            name: "ranger-mk1".into(),
            cause: None,
        }
    }

    fn hint_for(text: &str, s: Option<Status>) -> String {
        hint(&parsed_text(text), s.as_ref()).unwrap_or_default()
    }

    #[test]
    fn drives_off_or_faulted_hint_at_on_whatever_the_mode() {
        let off = status(Mode::Off, DriveStatus::Off, 0, Motion::Holding);
        let faulted = status(Mode::Cartesian, DriveStatus::Faulted, 31, Motion::Holding);
        for text in [
            "ER20 Cmd BG rejected",
            "ER20 Cmd RC rejected",
            "ER20 Cmd jB rejected",
        ] {
            assert!(hint_for(text, Some(off.clone())).contains("`armgate on`"));
            let h = hint_for(text, Some(faulted.clone()));
            assert!(h.contains("`armgate on`") && h.contains("ER31"), "{h}");
        }
        let starting = status(Mode::Off, DriveStatus::Starting, 0, Motion::Holding);
        assert!(hint_for("ER20 Cmd RC rejected", Some(starting)).contains("still starting"));
    }

    #[test]
    fn with_the_drives_running_the_mode_motion_and_goal_decide() {
        let s = status(Mode::Joint, DriveStatus::Running, 0, Motion::Holding);
        assert_eq!(
            hint_for("ER20 Cmd BG rejected", Some(s.clone())),
            "BG needs mode cartesian, the mode is joint: `armgate mode cartesian`"
        );
        assert!(hint_for("ER20 Cmd jB rejected", Some(s.clone())).contains("no joint goal"));
        assert!(hint_for("ER20 Cmd RC rejected", Some(s)).contains("`armgate mode off`"));
        let busy = status(
            Mode::Cartesian,
            DriveStatus::Running,
            0,
            Motion::CartesianMove,
        );
        assert!(hint_for("ER20 Cmd BG rejected", Some(busy)).contains("`armgate stop`"));
        // RC in mode off with idle, running drives: nothing to suggest.
        let idle_off = status(Mode::Off, DriveStatus::Running, 0, Motion::Holding);
        assert_eq!(
            hint(&parsed_text("ER20 Cmd RC rejected"), Some(&idle_off)),
            None
        );
        // Other refusals say enough by themselves.
        let idle = status(Mode::Cartesian, DriveStatus::Running, 0, Motion::Holding);
        assert_eq!(
            hint(&parsed_text("ER25 Cmd GT outside workspace"), Some(&idle)),
            None
        );
    }

    #[test]
    fn without_status_the_reason_text_decides() {
        // Texts are at most 30 characters on the wire (docs/protocol.md lists the reasons).
        assert!(hint_for("ER20 Cmd BG drives off", None).contains("`armgate on`"));
        assert!(hint_for("ER20 Cmd BG drives stopping", None).contains("`armgate on`"));
        assert!(hint_for("ER20 Cmd BG drive fault 31", None).contains("`armgate on`"));
        assert!(hint_for("ER20 Cmd RC drives starting", None).contains("starting"));
        assert!(hint_for("ER20 Cmd RC drives settling", None).contains("in a moment"));
        assert!(hint_for("ER20 Cmd BG needs mode 2", None).contains("`armgate mode cartesian`"));
        assert!(hint_for("ER20 Cmd RC needs mode 0", None).contains("`armgate mode off`"));
        assert!(hint_for("ER20 Cmd jE busy", None).contains("`armgate stop`"));
        assert!(hint_for("ER20 Cmd BG no goal", None).contains("goal"));
        assert!(hint_for("ER20 Cmd VE no via point 0", None).contains("via point 0"));
        // The reason wins over the state: it is what the controller checked.
        let running = status(Mode::Off, DriveStatus::Running, 0, Motion::Holding);
        assert!(hint_for("ER20 Cmd RC drives settling", Some(running)).contains("in a moment"));
        let old = hint_for("ER20 Cmd BG rejected", None);
        assert!(
            old.contains("mode cart") && old.contains("armgate on"),
            "{old}"
        );
        assert_eq!(hint(&parsed_text("ER11 Arm did not start"), None), None);
        assert_eq!(hint(&parsed_text("ER26 Cmd jG j5 < 0.785"), None), None);
    }
}
